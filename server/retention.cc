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

RetentionPlan PlanRetention(JobStore& store, const BlobStore& blobs, std::int64_t cutoff_unix_ms) {
  RetentionPlan plan;
  std::set<std::string> expiring, kept;
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
  return plan;
}

}  // namespace endorecon::server
