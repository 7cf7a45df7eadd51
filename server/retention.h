// Retention: the clips, results and checkpoints of jobs that finished (SUCCEEDED, FAILED,
// CANCELLED) before a cutoff are deleted; each job's record stays, marked expired. A blob that any
// other job still references (a queued or running job, or a finished one inside the retention
// period) is never deleted: the same content may belong to several jobs. A SUCCEEDED job whose
// DICOM results are still to be sent (a send PENDING or SENDING) is kept until its sends settle.
// Files that no job references at all are deleted once they are old enough (see RetentionPlan).
#pragma once

#include <cstdint>
#include <filesystem>
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
  // Files no job references, last written before the orphan cutoff: a running job's earlier
  // checkpoints, uploads never submitted, results a server refused, partial uploads given up.
  std::vector<BlobStore::StoredFile> orphans;
  std::int64_t orphan_bytes = 0;
};

// Jobs finished before `cutoff_unix_ms` expire (none for kKeepJobs); files no job references that
// were last written before `orphan_cutoff` go too (none for file_time_type::min()). Reads only, so
// it also serves the dry run.
inline constexpr std::int64_t kKeepJobs = std::numeric_limits<std::int64_t>::min();
RetentionPlan PlanRetention(
    JobStore& store, const BlobStore& blobs, std::int64_t cutoff_unix_ms,
    std::filesystem::file_time_type orphan_cutoff = std::filesystem::file_time_type::min());

}  // namespace endorecon::server
