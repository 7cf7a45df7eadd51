#include "server/retention.h"

#include <filesystem>
#include <set>

#include "server/job_states.h"

namespace endorecon::server {
namespace {

void AddBlobs(const v1::Job& job, std::set<std::string>& digests) {
  for (const auto& file : job.clip().files()) digests.insert(file.sha256());
  for (const auto& file : job.result().files()) digests.insert(file.sha256());
  if (!job.checkpoint().sha256().empty()) digests.insert(job.checkpoint().sha256());
}

}  // namespace

RetentionPlan PlanRetention(JobStore& store, const BlobStore& blobs, std::int64_t cutoff_unix_ms,
                            std::filesystem::file_time_type orphan_cutoff) {
  RetentionPlan plan;
  std::set<std::string> expiring, kept;
  // Listed before the jobs are read: a file stored after the scan is not listed, so it cannot be
  // taken for an orphan that a job the scan missed references.
  const auto files = orphan_cutoff > std::filesystem::file_time_type::min()
                         ? blobs.Files()
                         : std::vector<BlobStore::StoredFile>{};
  store.Scan([&](const StoredJob& stored) {
    const auto& job = stored.job;
    if (job.expired_unix_ms() > 0) return;
    if (Settled(job) && job.finished_unix_ms() < cutoff_unix_ms) {
      plan.jobs.push_back(job);
      AddBlobs(job, expiring);
    } else {
      AddBlobs(job, kept);
    }
  });
  for (const auto& digest : expiring) {
    if (kept.count(digest)) {
      ++plan.kept_shared;
    } else if (blobs.Has(digest)) {
      plan.blobs.push_back(digest);
      plan.bytes += static_cast<std::int64_t>(std::filesystem::file_size(blobs.PathOf(digest)));
    }
  }
  for (const auto& file : files) {
    if (file.written >= orphan_cutoff || expiring.count(file.sha256) || kept.count(file.sha256)) continue;
    plan.orphans.push_back(file);
    plan.orphan_bytes += file.bytes;
  }
  return plan;
}

}  // namespace endorecon::server
