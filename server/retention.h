// Retention: the clips, results and checkpoints of jobs that finished (SUCCEEDED, FAILED,
// CANCELLED) before a cutoff are deleted; each job's record stays, marked expired. A blob that any
// other job still references (a queued or running job, or a finished one inside the retention
// period) is never deleted: the same content may belong to several jobs. A SUCCEEDED job whose
// DICOM results are still to be sent (a send PENDING or SENDING) is kept until its sends settle.
// Files that no job references at all are deleted once they are old enough (OrphanCutoff).
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "server/blob_store.h"
#include "server/job_store.h"

namespace endorecon::server {

struct RetentionPlan {
  std::vector<v1::Job> jobs;       // finished before the cutoff and not expired yet
  std::vector<std::string> blobs;  // digests referenced only by those jobs, present in the store
  std::int64_t bytes = 0;          // the size of those blobs
  std::int64_t kept_shared = 0;    // blobs of those jobs kept because other jobs reference them
  std::int64_t kept_uploading = 0;  // and because an upload not yet submitted brings them
  // Files no job references: a running job's earlier checkpoints, uploads never submitted, results a
  // server refused, partial uploads given up. After OrphanWatch::Sift, only those due.
  std::vector<BlobStore::StoredFile> orphans;
  std::int64_t orphan_bytes = 0;
  std::int64_t orphans_waiting = 0;  // (Sift) files no job references that are not due yet
  // Files no job references that an upload not yet submitted brings: no orphans while it does, but
  // found no job's all the same (OrphanWatch), so that once the upload is given up they go
  // --orphan-hours after they arrived, not --orphan-hours after that (found 2026-12-07).
  std::vector<BlobStore::StoredFile> uploading;
};

// When a file no job references goes: last written before `written_before` and first found so
// (OrphanWatch) before `found_before_unix_ms`. The default: never.
struct OrphanCutoff {
  std::filesystem::file_time_type written_before = std::filesystem::file_time_type::min();
  std::int64_t found_before_unix_ms = std::numeric_limits<std::int64_t>::min();
};

inline constexpr std::int64_t kKeepJobs = std::numeric_limits<std::int64_t>::min();

// Adds the digests of `job`'s files (clip, result, checkpoint) to `digests`.
void AddJobFiles(const v1::Job& job, std::set<std::string>& digests);

// The cutoffs of the flags: jobs finished more than `retention_days` ago (kKeepJobs for 0), files
// last written and first found no job's more than `orphan_hours` ago (never, for 0).
std::int64_t JobCutoff(double retention_days);
OrphanCutoff OrphanCutoffFor(double orphan_hours);

// A content some tenant's upload not yet submitted brings (UploadLedger::Holds): kept, as a job's
// is. Without it, deleting one tenant's job deleted the files another tenant's interrupted upload of
// the same content had sent, and that upload had to send them again (found 2026-12-06).
using UploadingFn = std::function<bool(const std::string& sha256)>;

// The jobs not expired yet that `expires` picks expire, with the blobs only they reference (and no
// upload brings: `uploading`); of `files` (BlobStore::Files), those no job references and no upload
// brings are the plan's orphans (partial files whoever's they are). The files are listed before the
// plan reads the jobs, so a file stored after the listing cannot be taken for an orphan that a job the
// scan missed references; the listing walks the store's folders, so it belongs outside the
// coordinator's lock. Reads only.
RetentionPlan PlanExpiry(JobStore& store, const BlobStore& blobs,
                         const std::function<bool(const v1::Job&)>& expires,
                         const std::vector<BlobStore::StoredFile>& files = {},
                         const UploadingFn& uploading = {});

// Jobs settled (Settled: finished, their sends too) before `cutoff_unix_ms` expire (none for
// kKeepJobs); PlanExpiry. Reads only, so it also serves the dry run.
RetentionPlan PlanRetention(JobStore& store, const BlobStore& blobs, std::int64_t cutoff_unix_ms,
                            const std::vector<BlobStore::StoredFile>& files = {},
                            const UploadingFn& uploading = {});

}  // namespace endorecon::server
