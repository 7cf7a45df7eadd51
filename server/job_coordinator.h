// Every change of a job's state goes through here, so the durable store, the queue, the leases,
// the watchers and the metrics never disagree:
//
//   Submit -> QUEUED -> (Lease) RUNNING -> (Complete) SUCCEEDED
//                 ^                |----> (Fail, not retryable; or attempts used up) FAILED
//                 |-- (lease expired, Fail retry, release) --|
//   Cancel: QUEUED -> CANCELLED at once; RUNNING -> CANCELLED when the worker next reports
//   (or its lease expires).
//
// An attempt counts when a worker vanishes (lease expiry) or fails retryably; a clean hand-back
// (release) does not count. The job store is written before anything else is told.
//
// Jobs belong to the submitter's tenant. A caller limited to one tenant (Principal) sees only that
// tenant's jobs: any other id is NOT_FOUND with the same message as an id that does not exist.
#pragma once

#include <chrono>
#include <mutex>
#include <optional>
#include <string>

#include "endorecon/v1/job_service.pb.h"
#include "endorecon/v1/worker_service.pb.h"
#include "server/blob_store.h"
#include "server/job_store.h"
#include "server/lease_table.h"
#include "server/metrics.h"
#include "server/principal.h"
#include "server/retention.h"
#include "server/scheduler.h"
#include "server/tenant_quotas.h"
#include "server/watch_hub.h"
#include "server/worker_registry.h"

namespace endorecon::server {

struct CoordinatorParts {
  JobStore& store;
  BlobStore& blobs;
  Scheduler& scheduler;
  LeaseTable& leases;
  WorkerRegistry& workers;
  WatchHub& hub;
  Metrics& metrics;
};

class JobCoordinator {
 public:
  JobCoordinator(CoordinatorParts parts, int max_attempts, TenantQuotas quotas = {});

  // Queues the QUEUED jobs of the store and re-grants the leases of its RUNNING ones.
  void Recover();

  // Queues a job of the caller's tenant. Throws kInvalidArgument (bad manifest or option, naming
  // it), kFailedPrecondition (a clip file not uploaded yet, naming it), kResourceExhausted (the
  // tenant's max_jobs or max_bytes quota, naming it and the numbers).
  v1::Job Submit(const v1::SubmitRequest& request, const Principal& caller);
  // Throws kResourceExhausted when storing `manifest` in full would take the caller's tenant over
  // its max_bytes quota (checked before an upload writes anything).
  void CheckUploadQuota(const v1::Manifest& manifest, const Principal& caller);
  // Throws kNotFound (also for another tenant's job).
  v1::Job Get(const std::string& id, const Principal& caller);
  // Jobs newest first (see JobStore::List), the caller's tenant only unless it sees all tenants.
  JobStore::Page List(const std::vector<v1::JobState>& states, int limit, std::int64_t before_seq,
                      const Principal& caller);
  // Throws kNotFound (also for another tenant's job), kFailedPrecondition when the job is already finished.
  v1::Job Cancel(const std::string& id, const Principal& caller);

  struct Granted {
    v1::Job job;
    std::string lease_id;
    int attempt = 1;
  };
  // Leases the next job to `worker_id`, waiting until `deadline`; nullopt when there is none.
  std::optional<Granted> Lease(const std::string& worker_id, Clock::time_point deadline);
  // Renews the lease and records progress, preview or checkpoint; says whether to go on. Sets
  // `job_id` to the lease's job when the lease is held.
  v1::ProgressReply::Action Report(const v1::ProgressUpdate& update, std::string* job_id = nullptr);
  // Throws kFailedPrecondition when the lease is not held or a result file is not uploaded.
  v1::Job Complete(const v1::CompleteRequest& request);
  // Throws kFailedPrecondition when the lease is not held.
  v1::Job Fail(const v1::FailRequest& request);
  // The leased job. Throws kFailedPrecondition unless `lease_id` is held (workers download only
  // while leasing, and only their job's files).
  v1::Job CheckLease(const std::string& lease_id);
  // Takes back every lease expired at `now`: requeues the job or fails it after max attempts.
  void ExpireLeases(Clock::time_point now);
  // Retention: deletes the files of jobs finished before `cutoff_unix_ms` that no other job shares
  // and marks those jobs expired (PlanRetention). Returns what it did.
  RetentionPlan ExpireFinishedBefore(std::int64_t cutoff_unix_ms);

 private:
  StoredJob Load(const std::string& id);
  // Load, but another tenant's job is kNotFound exactly as a missing one.
  StoredJob LoadVisible(const std::string& id, const Principal& caller);
  StoredJob LoadLeased(const std::string& lease_id);
  // Writes `job` to the store, then tells the watchers.
  void Save(const v1::Job& job);
  void Finish(v1::Job& job, v1::JobState state, const std::string& error);
  void Requeue(StoredJob& stored, bool count_attempt, const std::string& reason);

  CoordinatorParts parts_;
  int max_attempts_;
  TenantQuotas quotas_;
  std::mutex mutex_;
};

// Milliseconds since the Unix epoch, as stored in jobs.
std::int64_t NowUnixMs();

}  // namespace endorecon::server
