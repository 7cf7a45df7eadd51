// Runs one leased job on one device, in this process: fetch the clip (and the last checkpoint,
// when resuming), train with the engine while a ProgressReporter streams progress, previews and
// checkpoints, then upload every result file and complete the job. How it ends:
//   results uploaded -> Complete;  cancelled or lease lost -> nothing more to say;
//   shutting down (SIGTERM) -> Fail(retry, release): the job goes back to the queue without
//   counting an attempt and resumes from its last checkpoint elsewhere;
//   bad clip or options -> Fail (not retried);  anything else -> Fail(retry).
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <string>

#include "endorecon/v1/worker_service.pb.h"
#include "worker/runtime/worker_client.h"
#include "worker/runtime/worker_metrics.h"

namespace endorecon::worker {

struct RunnerSettings {
  std::filesystem::path work_dir;             // the job's files live in <work_dir>/<job id>/ while it runs
  std::chrono::milliseconds heartbeat{2000};  // report interval (the server's)
  std::chrono::milliseconds lease_ttl{30000};  // a lease not renewed within this expires (the server's)
  double preview_interval_s = 30;
  double checkpoint_interval_s = 120;
  // A job that fails while the scratch folder has less than this free is handed back without
  // counting an attempt (the disk, not the job, was at fault), and no job is leased until there is
  // this much free again (ScratchFree).
  std::int64_t min_free_bytes = std::int64_t{256} << 20;
};

// Bytes free on the scratch folder's filesystem (its nearest existing parent's while it does not
// exist; -1 when that cannot be read).
std::int64_t ScratchFree(const std::filesystem::path& work_dir);
// Removes the job folders an earlier run of this worker left in its scratch folder (a kill -9 skips
// the removal after each job; the server gives such a job to a worker again, from its checkpoint).
// Called at start, before any job runs; a scratch folder is one worker's own. Returns how many.
int RemoveLeftoverJobs(const std::filesystem::path& work_dir);
// A worker's default scratch folder: `temp`/endorecon-ID (the ID: HOST-PID unless --id is given).
std::filesystem::path DefaultWorkDir(const std::filesystem::path& temp, const std::string& worker_id);
// The file in a scratch folder whose lock its worker holds while it runs (common/folder_lock.h).
inline constexpr const char* kWorkerLockFile = "worker.lock";
// The default scratch folders (`temp`/endorecon-ID) of earlier workers whose process is gone (a kill
// -9, a crash): no later worker has their id (HOST-PID, or an --id not given again), so
// RemoveLeftoverJobs never saw them and their patient data stayed for good. A folder is gone when
// nobody holds its kWorkerLockFile and that file is a minute old (a worker starting takes it at
// once), or, left by a worker of before the lock, when it is named HOST-PID after a process that is
// gone. Only this user's folders. Returns how many.
int RemoveDeadWorkersFolders(const std::filesystem::path& temp, const std::string& host);

// Never throws for the job's own failures (they are reported to the server) nor for a lease that
// is gone (nothing is then handed back); removes the job's folder however the run ends. Returns
// true when the job failed on a full scratch folder (and was handed back uncounted): the caller
// then leaves jobs to other workers for a while.
bool RunLeasedJob(WorkerClient& client, const v1::LeaseResponse& lease, const Device& device,
                  const RunnerSettings& settings, WorkerMetrics& metrics,
                  const std::atomic<bool>& shutting_down);

}  // namespace endorecon::worker
