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
//
// Every call that writes returns only once the job store has committed its writes, but waits for
// that commit outside the coordinator's lock, so calls that arrive meanwhile stage theirs for the
// next commit (JobStore's group commit). The queue, leases and watchers may learn of a change up
// to one commit before it is on disk; a crash in between loses that change together with the
// memory that knew it, and no caller was told it happened.
#pragma once

#include <chrono>
#include <functional>
#include <mutex>
#include <optional>
#include <string>
#include <type_traits>

#include "endorecon/v1/job_service.pb.h"
#include "endorecon/v1/worker_service.pb.h"
#include "server/blob_holders.h"
#include "server/blob_store.h"
#include "server/job_store.h"
#include "server/lease_table.h"
#include "server/metrics.h"
#include "server/orphan_watch.h"
#include "server/pacs_directory.h"
#include "server/principal.h"
#include "server/retention.h"
#include "server/scheduler.h"
#include "server/tenant_quotas.h"
#include "server/unix_time.h"
#include "server/upload_ledger.h"
#include "server/upload_owner.h"
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

// The DICOM side of jobs: which PACS exist, and who retrieves recordings and sends results
// (server/dicom_gateway.h). Without it, jobs that name a PACS are refused.
struct DicomHooks {
  const PacsDirectory* pacs = nullptr;
  std::string uid_root;
  std::function<void(const std::string& job_id)> retrieve;  // the job waits for its recording
  std::function<void(const std::string& job_id)> send;      // the job has PENDING sends
};

class JobCoordinator {
 public:
  // `clock` stamps leases (grants, renewals, re-grants on recovery); tests pass their own to move
  // time without waiting.
  JobCoordinator(CoordinatorParts parts, int max_attempts, TenantQuotas quotas = {},
                 std::function<Clock::time_point()> clock = Clock::now);

  void SetDicomHooks(DicomHooks hooks);

  // Queues the QUEUED jobs of the store (those still waiting for a PACS retrieval go back to the
  // retrieve hook), re-grants the leases of its RUNNING ones and hands SUCCEEDED jobs with PENDING
  // or SENDING sends back to the send hook.
  void Recover();
  // Keeps the tenants' uploads not yet submitted in `file` (UploadLedger::KeepIn), read now.
  void KeepUploadsIn(const std::filesystem::path& file);
  // Keeps when files no job references were first found so in `file` (OrphanWatch::KeepIn), read now.
  void KeepOrphansIn(const std::filesystem::path& file);
  // When a token label was revoked (Unix ms; 0: it was not), for the reason of a lease lost to it
  // (CallGuard::TokenRevokedAt). Set before serving.
  void SetTokenRevokedAt(std::function<std::int64_t(const std::string&)> revoked_at) {
    token_revoked_at_ = std::move(revoked_at);
  }

  // Queues a job of the caller's tenant; a job naming a PACS study waits for its retrieval first
  // (the retrieve hook), and the recording's bytes count against the tenant once retrieved. Throws
  // kInvalidArgument (bad manifest, option, UID or PACS name, naming it), kFailedPrecondition (a
  // clip file not uploaded yet, naming it), kResourceExhausted (the tenant's max_jobs or max_bytes
  // quota, naming it and the numbers). With request.validate_only it checks the same (the clip may be
  // a sizes-only listing, not uploaded yet) and returns the job it would queue, without an id,
  // queueing nothing.
  v1::Job Submit(const v1::SubmitRequest& request, const Principal& caller);
  // Throws kResourceExhausted when storing `manifest` in full would take the caller's tenant over
  // its max_jobs or max_bytes quota: the check of a listing before an upload (QueryUpload), which does
  // not count the tenant's uploads not yet submitted (a sizes-only listing has no digests to tell an
  // upload resumed from another).
  void CheckUploadQuota(const v1::Manifest& manifest, const Principal& caller);
  // The same as an upload of `manifest` starts, before it writes anything, counting the tenant's
  // other uploads not yet submitted too; then notes this one's files as the tenant's (UploadLedger)
  // until they are submitted, dropped (Uploads) or retention forgets them.
  void AdmitUpload(const v1::Manifest& manifest, const Principal& caller);
  // The uploads not yet submitted of the caller's tenant (an admin's: every tenant's, or the one
  // it names); with `drop`, forgets them and deletes their files that no job, and no other tenant's
  // upload, holds (a partial being written is kept). A client naming another tenant is refused
  // (kPermissionDenied); an admin's drop names its tenant (kInvalidArgument otherwise).
  v1::UploadsResponse Uploads(const v1::UploadsRequest& request, const Principal& caller);
  // Whose uploads a client's are (its tenant's) and a worker's (its served tenant's; a worker of
  // every tenant is trusted with every stored content): a stored content the tenant does not hold is
  // sent again before the caller's jobs may name it (BlobHolders).
  UploadOwner ClientUploadOwner(const Principal& caller);
  // Every tenant's uploads not yet submitted, in bytes as declared (the metrics' gauge: the ledger in
  // memory, no file is read).
  std::int64_t PendingUploadBytes();
  UploadOwner WorkerUploadOwner(const std::optional<std::string>& served_tenant);
  // The same for a recording retrieved for job `id`, before it goes into the blob store: the job's
  // tenant pays for it.
  void CheckRetrievalQuota(const std::string& id, const v1::Manifest& recording);
  // Throws kNotFound (also for another tenant's job).
  v1::Job Get(const std::string& id, const Principal& caller);
  // Jobs newest first (see JobStore::List), the caller's tenant only unless it sees all tenants,
  // after `after_job` (the last job of the page before, as the page token names it; "": from the
  // newest). Throws kInvalidArgument for a job the caller cannot see.
  JobStore::Page List(const std::vector<v1::JobState>& states, int limit, const std::string& after_job,
                      const Principal& caller);
  // Throws kNotFound (also for another tenant's job), kFailedPrecondition when the job is already finished.
  v1::Job Cancel(const std::string& id, const Principal& caller);
  // Deletes a settled job's files now, as retention would (PlanExpiry): the record stays, marked
  // expired, and its bytes stop counting against its tenant's byte quota. FAILED_PRECONDITION for a
  // job not settled (queued, running, or with DICOM sends to go) or already expired.
  v1::Job Delete(const std::string& id, const Principal& caller);

  struct Granted {
    v1::Job job;
    std::string lease_id;
    int attempt = 1;
  };
  // Leases the next job to `worker_id`, waiting until `deadline`, or until `cancelled` (asked twice a
  // second) says the call was cancelled; nullopt when there is none. With `tenant`, only that
  // tenant's jobs (a worker whose token serves one tenant). `token`: the one the call carried.
  std::optional<Granted> Lease(const std::string& worker_id, Clock::time_point deadline,
                               const std::optional<std::string>& tenant = std::nullopt,
                               const std::function<bool()>& cancelled = {}, const LeaseToken& token = {});
  // Renews the lease (noting the `token` the call carried) and records progress, preview or
  // checkpoint; says whether to go on. Sets `job_id` to the lease's job when the lease is held, and
  // `register_again` to whether the lease's worker is unknown to the registry (the server restarted
  // since it registered). A worker serving one tenant (`served_tenant`) names as checkpoint only
  // content that tenant holds (BlobHolders); another is left out.
  v1::ProgressReply::Action Report(const v1::ProgressUpdate& update, const LeaseToken& token = {},
                                   std::string* job_id = nullptr, bool* register_again = nullptr,
                                   const std::optional<std::string>& served_tenant = std::nullopt);
  // Throws kFailedPrecondition when the lease is not held or a result file is not uploaded (for a
  // worker serving one tenant: also content that tenant does not hold, reported the same). Sets
  // `job_id` to the lease's job once the lease is found (the audit line of a refusal names it).
  v1::Job Complete(const v1::CompleteRequest& request,
                   const std::optional<std::string>& served_tenant = std::nullopt,
                   std::string* job_id = nullptr);
  // Throws kFailedPrecondition when the lease is not held.
  v1::Job Fail(const v1::FailRequest& request);
  // The leased job. Throws kFailedPrecondition unless `lease_id` is held (workers download only
  // while leasing, and only their job's files).
  v1::Job CheckLease(const std::string& lease_id);
  // Takes back every lease expired at `now`: requeues the job or fails it after max attempts. A lease
  // whose worker's token had expired (its calls refused, so it could not renew) costs no attempt: a
  // token expiring mid-job failed jobs that had nothing wrong with them (found 2026-12-06).
  // `server_refusing` (CallGuard::OpenFailure: the server refused every call meanwhile) makes each
  // expiry the server's fault: requeued with no attempt counted, the reason naming it. So is a lease
  // re-granted at the server's start whose worker never called since (Lease::restored).
  void ExpireLeases(Clock::time_point now, const std::string& server_refusing = "");
  // Retention: deletes the files of jobs finished before `cutoff_unix_ms` that no other job shares
  // and marks those jobs expired, and deletes the files no job references that `orphan_cutoff` makes
  // due (PlanRetention, OrphanWatch::Sift). Returns what it did.
  RetentionPlan ExpireFinishedBefore(std::int64_t cutoff_unix_ms, const OrphanCutoff& orphan_cutoff = {});

  // Asks for the DICOM results of a SUCCEEDED job of the caller's tenant to go (again) to the PACS
  // `destination`. Throws kNotFound (job, also another tenant's, or PACS), kFailedPrecondition (not
  // SUCCEEDED, no dicom/ results, results deleted by retention).
  v1::Job RequestSend(const std::string& id, const std::string& destination, const Principal& caller);
  // Applies `change` to a job and saves it (watchers see it); for the retrieval and the sends,
  // which change nothing else. Returns the job as saved. Throws kNotFound.
  v1::Job Update(const std::string& id, const std::function<void(v1::Job&)>& change);
  // The recording of a job submitted by Study UID is in the blob store: the job gets it as its clip
  // and is queued for a worker (if still QUEUED). Throws kResourceExhausted when it would take the
  // job's tenant over its max_bytes quota (the job is then not changed).
  void RetrievalDone(const std::string& id, const v1::Manifest& clip);
  // The retrieval failed: the job FAILS with the reason.
  void RetrievalFailed(const std::string& id, const std::string& reason);

 private:
  // Runs `body` under the lock, then waits (outside it) until the store has committed what `body`
  // wrote. When `body` throws, what it staged goes to disk with the next commit.
  template <typename Body>
  auto Locked(Body&& body) -> decltype(body()) {
    if constexpr (std::is_void_v<decltype(body())>) {
      {
        std::lock_guard lock(mutex_);
        body();
      }
      parts_.store.Flush();
    } else {
      auto result = [&] {
        std::lock_guard lock(mutex_);
        return body();
      }();
      parts_.store.Flush();
      return result;
    }
  }
  v1::ProgressReply::Action ReportLocked(const v1::ProgressUpdate& update, const LeaseToken& token,
                                         std::string* job_id, bool* register_again,
                                         const std::optional<std::string>& served_tenant);
  UploadOwner UploadOwnerOf(const std::string& tenant);
  // RequireBlobs, with the content `tenant` does not hold (BlobHolders) reported as not uploaded;
  // the server's log names `who` named stored content that way.
  void RequireHeld(const v1::Manifest& manifest, const std::string& what, const std::string& tenant,
                   const std::string& who);
  // Settles the uploads of uploads.json noted by a server of before 2026-12-06 (UploadLedger::Legacy),
  // once the jobs' holdings are known.
  void SettleLegacyUploads();
  // Deletes a blob (or any stored file) and forgets who held it.
  void RemoveBlob(const std::string& digest);
  void RemoveFile(const BlobStore::StoredFile& file);
  StoredJob Load(const std::string& id);
  // Load, but another tenant's job is kNotFound exactly as a missing one.
  StoredJob LoadVisible(const std::string& id, const Principal& caller);
  StoredJob LoadLeased(const std::string& lease_id);
  // Throws kResourceExhausted when `tenant` keeping the files of `adding` (and `pending` bytes of its
  // uploads not yet submitted) would pass its max_bytes (naming the largest), or, when the call
  // `adds_job`, when it has max_jobs jobs queued or running. The caller holds the lock.
  void CheckQuotas(const std::string& tenant, const v1::Manifest& adding, bool adds_job,
                   std::int64_t pending = 0);
  // Writes `job` to the store, then tells the watchers.
  void Save(const v1::Job& job);
  void Finish(v1::Job& job, v1::JobState state, const std::string& error);
  void Requeue(StoredJob& stored, bool count_attempt, const std::string& reason);

  CoordinatorParts parts_;
  DicomHooks dicom_;
  int max_attempts_;
  TenantQuotas quotas_;
  UploadLedger uploads_;  // under mutex_
  OrphanWatch orphans_;   // under mutex_
  BlobHolders holders_;   // under mutex_
  std::function<std::int64_t(const std::string&)> token_revoked_at_;
  std::function<Clock::time_point()> clock_;
  std::mutex mutex_;
};

}  // namespace endorecon::server
