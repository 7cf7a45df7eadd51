#include "server/retention.h"

#include <chrono>
#include <filesystem>
#include <set>

#include "server/job_states.h"
#include "server/unix_time.h"

namespace endorecon::server {
void AddJobFiles(const v1::Job& job, std::set<std::string>& digests) {
  for (const auto& file : job.clip().files()) digests.insert(file.sha256());
  for (const auto& file : job.result().files()) digests.insert(file.sha256());
  if (!job.checkpoint().sha256().empty()) digests.insert(job.checkpoint().sha256());
}

std::int64_t JobCutoff(double retention_days) {
  if (retention_days <= 0) return kKeepJobs;
  return NowUnixMs() - static_cast<std::int64_t>(retention_days * 86'400'000.0);
}

OrphanCutoff OrphanCutoffFor(double orphan_hours) {
  if (orphan_hours <= 0) return {};
  const std::chrono::milliseconds hours(static_cast<std::int64_t>(orphan_hours * 3'600'000.0));
  return {std::filesystem::file_time_type::clock::now() - hours, NowUnixMs() - hours.count()};
}

RetentionPlan PlanRetention(JobStore& store, const BlobStore& blobs, std::int64_t cutoff_unix_ms,
                            const std::vector<BlobStore::StoredFile>& files, const UploadingFn& uploading) {
  return PlanExpiry(
      store, blobs,
      [&](const v1::Job& job) { return Settled(job) && job.finished_unix_ms() < cutoff_unix_ms; }, files,
      uploading);
}

RetentionPlan PlanExpiry(JobStore& store, const BlobStore& blobs,
                         const std::function<bool(const v1::Job&)>& expires,
                         const std::vector<BlobStore::StoredFile>& files, const UploadingFn& uploading) {
  const auto brought = [&](const std::string& digest) { return uploading && uploading(digest); };
  RetentionPlan plan;
  std::set<std::string> expiring, kept;
  store.Scan([&](const StoredJob& stored) {
    const auto& job = stored.job;
    if (job.expired_unix_ms() > 0) return;
    if (expires(job)) {
      plan.jobs.push_back(job);
      AddJobFiles(job, expiring);
    } else {
      AddJobFiles(job, kept);
    }
  });
  for (const auto& digest : expiring) {
    if (kept.count(digest)) {
      ++plan.kept_shared;
    } else if (brought(digest)) {
      ++plan.kept_uploading;
    } else if (const auto bytes = blobs.SizeOf(digest)) {
      plan.blobs.push_back(digest);
      plan.bytes += *bytes;
    }
  }
  for (const auto& file : files) {
    // A partial is given up at the cutoff even where its content is a job's: that content is stored
    // whole, and the partial is another tenant's upload of it (BlobHolders) left unfinished.
    if (!file.partial && (expiring.count(file.sha256) || kept.count(file.sha256))) continue;
    if (!file.partial && brought(file.sha256)) {
      plan.uploading.push_back(file);
      continue;
    }
    plan.orphans.push_back(file);
    plan.orphan_bytes += file.bytes;
  }
  return plan;
}

}  // namespace endorecon::server
