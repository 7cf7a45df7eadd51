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
#include <filesystem>

#include "endorecon/v1/worker_service.pb.h"
#include "worker/runtime/worker_client.h"
#include "worker/runtime/worker_metrics.h"

namespace endorecon::worker {

struct RunnerSettings {
  std::filesystem::path work_dir;             // the job's files live in <work_dir>/<job id>/ while it runs
  std::chrono::milliseconds heartbeat{2000};  // report interval (the server's)
  double preview_interval_s = 30;
  double checkpoint_interval_s = 120;
};

// Never throws for the job's own failures (they are reported to the server); throws Error only
// when the server cannot be told.
void RunLeasedJob(WorkerClient& client, const v1::LeaseResponse& lease, const Device& device,
                  const RunnerSettings& settings, WorkerMetrics& metrics,
                  const std::atomic<bool>& shutting_down);

}  // namespace endorecon::worker
