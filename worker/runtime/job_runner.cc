#include "worker/runtime/job_runner.h"

#include <signal.h>
#include <spdlog/spdlog.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstring>
#include <nlohmann/json.hpp>
#include <optional>
#include <string_view>
#include <thread>

#include "common/clip_files.h"
#include "common/error.h"
#include "common/folder_lock.h"
#include "common/manifest.h"
#include "common/replace_all.h"
#include "common/sha256.h"
#include "common/warning_pacer.h"
#include "worker/engine/reconstruct.h"
#include "worker/runtime/dicom_job.h"
#include "worker/runtime/job_options.h"
#include "worker/runtime/job_preparation.h"
#include "worker/runtime/preview_png.h"
#include "worker/runtime/progress_reporter.h"

namespace endorecon::worker {
namespace fs = std::filesystem;
namespace {

v1::Progress ToProto(const Progress& p) {
  v1::Progress out;
  out.set_iteration(p.iteration);
  out.set_total_iterations(p.total_iterations);
  out.set_seconds(p.seconds);
  out.set_eta_s(p.eta_s);
  out.set_loss(p.loss);
  out.set_train_psnr(p.train_psnr);
  out.set_heldout_psnr(p.heldout_psnr);
  out.set_depth_rmse(p.depth_rmse);
  out.set_samples_per_second(p.samples_per_second);
  out.set_phase(p.phase);
  return out;
}

// Uploads a checkpoint file the engine just wrote, as a blob named by its file name.
v1::FileEntry UploadCheckpoint(WorkerClient& client, const fs::path& path) {
  v1::Manifest manifest;
  auto* entry = manifest.add_files();
  entry->set_path(path.filename().string());
  entry->set_size(static_cast<std::int64_t>(fs::file_size(path)));
  entry->set_sha256(Sha256File(path));
  client.PutFiles(path.parent_path(), manifest);
  return *entry;
}

std::string SummaryJson(const ReconstructSummary& summary) {
  nlohmann::json json{{"iterations", summary.iterations},
                      {"train_seconds", summary.train_seconds},
                      {"train_psnr", summary.train_psnr},
                      {"heldout_psnr", summary.heldout_psnr},
                      {"metrics", fs::path(summary.metrics_path).filename().string()}};
  if (summary.budget_advised_s > 0) json["budget_advised_s"] = summary.budget_advised_s;
  if (!summary.warnings.empty()) json["warnings"] = summary.warnings;
  if (summary.time_budget_s > 0) {
    json["time_budget_s"] = summary.time_budget_s;
    json["run_seconds"] = summary.run_seconds;
  }
  return json.dump();
}

// What may pass while a call is retried, besides the server being unreachable.
struct RetryAlso {
  bool token_change = false;  // UNAUTHENTICATED: --token-file is read again when it changes
  // When set, RESOURCE_EXHAUSTED for the server's data disk too (space may be freed), called at each
  // such refusal (the job's progress says so).
  std::function<void()> on_space_wait;
};

// Whether `e` is the server refusing an upload for its data disk's free space (UploadReceiver).
bool ServerDiskFull(const Error& e) {
  return e.code() == ErrorCode::kResourceExhausted &&
         std::string_view(e.what()).find("the server's data disk") != std::string_view::npos;
}

// Retries `call` (a call through `client`), a second apart or as soon as the server is back, while it
// fails UNAVAILABLE (or as `also` allows) and `go_on()` holds; the warning of each retry ends with
// `while_what`.
template <typename Call, typename GoOn>
auto RetryUnavailable(WorkerClient& client, Call&& call, GoOn&& go_on, const char* while_what,
                      RetryAlso also = {}) {
  WarningPacer pacer;
  while (true) {
    try {
      return call();
    } catch (const Error& e) {
      const bool refused = e.code() == ErrorCode::kUnauthenticated && also.token_change;
      // A full server disk fails no job that has its results (they were refused, the job failed
      // after three attempts of training again; found 2026-12-07): they wait here for space.
      const bool no_space = also.on_space_wait && ServerDiskFull(e);
      if ((e.code() != ErrorCode::kUnavailable && !refused && !no_space) || !go_on()) throw;
      int held = 0;
      if (pacer.Due(held)) {
        spdlog::warn("{}; retrying every {}{}{}{}", e.what(), no_space ? "10 s" : "second", while_what,
                     refused    ? " (write a valid worker token into --token-file)"
                     : no_space ? " (the results wait on this worker until space is freed on the server)"
                                : "",
                     held > 0 ? fmt::format(" ({} more failures since the last warning)", held) : "");
      }
      if (no_space) also.on_space_wait();
      client.PauseBeforeRetry(std::chrono::seconds(no_space ? 10 : 1));
    }
  }
}

// Retries `call` while the server is unreachable (a restart), for about `patience`.
template <typename Call>
auto WhileUnavailable(WorkerClient& client, Call&& call,
                      std::chrono::seconds patience = std::chrono::seconds(30)) {
  const auto give_up = std::chrono::steady_clock::now() + patience;
  return RetryUnavailable(
      client, std::forward<Call>(call), [&] { return std::chrono::steady_clock::now() <= give_up; }, "");
}

// Retries `call` while it fails UNAVAILABLE (a server restarting, or one whose upload slots are all
// taken by clients' uploads until the call's deadline) or UNAUTHENTICATED (the worker's token
// expired or was revoked, and a new one may be written into --token-file) as long as the lease is
// held: the server asked for no stop in its answers to the job's heartbeats (one that took the lease
// back says so when it answers again) and, with `patience`, answered one within it. Without it a
// server that is down is waited for: a restarted server keeps the leases for one lease time, and a
// wait of 30 s threw finished results away and cost the job an attempt when an upgrade took longer
// (found 2026-12-07). With `on_space_wait`, also while the server refuses an upload for want of space
// on its data disk; with `shutting_down`, only until it is set (a SIGTERM waited on a full disk for as
// long as it stayed full; found 2026-12-07).
template <typename Call>
auto WhileLeaseHeld(WorkerClient& client, const ProgressReporter& reporter, Call&& call,
                    const std::atomic<bool>* shutting_down = nullptr,
                    std::function<void()> on_space_wait = {},
                    std::optional<std::chrono::milliseconds> patience = std::nullopt) {
  return RetryUnavailable(
      client, std::forward<Call>(call),
      [&] {
        return !reporter.stop_requested() && !(shutting_down && shutting_down->load()) &&
               (!patience || std::chrono::steady_clock::now() - reporter.last_answer() < *patience);
      },
      " while the server holds the lease", {.token_change = true, .on_space_wait = std::move(on_space_wait)});
}

// `message` with the job's folder on this worker taken out of its paths: the user who reads it
// knows the clip, not the worker's scratch folder ("images/000005.png: cannot decode", not
// "/var/cache/endorecon-worker-0/3b714f29e295/clip/images/000005.png: cannot decode").
std::string InTheClip(std::string message, const fs::path& job_dir) {
  message = ReplaceAll(std::move(message), (job_dir / "clip").string() + "/", "");
  message = ReplaceAll(std::move(message), (job_dir / "clip").string(), "the clip");
  return ReplaceAll(std::move(message), job_dir.string() + "/", "");
}

// `message` with a raw recording's staged names (side_by_side.mp4, left/) replaced by the files and
// folders as the submitter named them (PrepareOptions.sources): first where the message holds them as
// the worker opened them, under `clip_dir` (a folder's name without its slash too: "left: it ends
// after ..." was left in the upload's name; found 2026-12-07), then where a name starts a path (not
// inside another word). Before InTheClip, which shortens `clip_dir`'s paths.
std::string InTheUsersNames(std::string message, const v1::Job& job, const std::filesystem::path& clip_dir) {
  const auto path_char = [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '/' || c == '.' || c == '-';
  };
  // Replaces `from` by `to` where no path character comes before it (`starts`) and, with `ends`,
  // none but a slash after it.
  const auto replace = [&](const std::string& from, const std::string& to, bool starts, bool ends) {
    for (std::size_t at = message.find(from); at != std::string::npos; at = message.find(from, at)) {
      const std::size_t end = at + from.size();
      if ((starts && at > 0 && path_char(message[at - 1])) ||
          (ends && end < message.size() && message[end] != '/' && path_char(message[end]))) {
        at = end;
        continue;
      }
      message.replace(at, from.size(), to);
      at += to.size();
    }
  };
  for (const auto& [staged, given] : job.prepare().sources()) {
    const auto bare = [](const std::string& name) {
      return name.size() > 1 && name.back() == '/' ? name.substr(0, name.size() - 1) : name;
    };
    replace((clip_dir / bare(staged)).string(), bare(given), false, true);
  }
  for (const auto& [staged, given] : job.prepare().sources()) replace(staged, given, true, false);
  return message;
}

void Tell(WorkerClient& client, const std::string& lease_id, const std::string& reason, bool retry,
          bool release) {
  v1::FailRequest request;
  request.set_lease_id(lease_id);
  request.set_reason(reason);
  request.set_retry(retry);
  request.set_release(release);
  try {
    const auto job = WhileUnavailable(client, [&] { return client.Fail(request); });
    spdlog::info("job {} handed back: {} -> {}", job.id(), reason, v1::JobState_Name(job.state()));
  } catch (const Error& e) {
    // Refused (the lease expired, or the job went to another worker) or not delivered: either way
    // the server's lease expiry decides the job, and the run still ends here.
    spdlog::warn("lease {}: not handed back: {}: {}", lease_id, ErrorCodeName(e.code()), e.what());
  }
}

// Removes a job's scratch folder however its run ends. Without it, a run whose hand-back failed
// (an exception out of the catch block) left the whole clip and results behind until the worker
// restarted (found by the fault campaign under TSan, where leases expire).
class JobFolder {
 public:
  explicit JobFolder(fs::path dir) : dir_(std::move(dir)) {}
  ~JobFolder() {
    std::error_code ignored;
    fs::remove_all(dir_, ignored);
  }
  JobFolder(const JobFolder&) = delete;
  JobFolder& operator=(const JobFolder&) = delete;
  const fs::path& path() const { return dir_; }

 private:
  fs::path dir_;
};

}  // namespace

std::int64_t ScratchFree(const std::filesystem::path& work_dir) {
  // The folder may not exist yet (made with the first job): its nearest existing parent's disk.
  fs::path probe = work_dir;
  std::error_code error;
  while (!probe.empty() && !fs::exists(probe, error) && probe.has_parent_path() &&
         probe != probe.parent_path())
    probe = probe.parent_path();
  const auto space = fs::space(probe, error);
  return error ? -1 : static_cast<std::int64_t>(space.available);
}

int RemoveLeftoverJobs(const std::filesystem::path& work_dir) {
  int removed = 0;
  std::error_code error;
  for (auto it = fs::directory_iterator(work_dir, error); !error && it != fs::directory_iterator();
       it.increment(error)) {
    std::error_code ignored;
    if (it->is_directory(ignored) && fs::remove_all(it->path(), ignored) > 0) ++removed;
  }
  return removed;
}

fs::path DefaultWorkDir(const fs::path& temp, const std::string& worker_id) {
  return temp / ("endorecon-" + worker_id);
}

namespace {

// A folder left by a worker that is gone, judged by its lock (or, without one, by its HOST-PID name).
bool LeftByAWorkerGone(const fs::path& folder, const std::string& name, const std::string& pid_prefix) {
  std::error_code error;
  const fs::path lock = folder / kWorkerLockFile;
  if (fs::is_regular_file(fs::symlink_status(lock, error))) {
    const auto written = fs::last_write_time(lock, error);
    return !error && fs::file_time_type::clock::now() - written > std::chrono::minutes(1) &&
           LockAbandoned(lock);
  }
  if (!name.starts_with(pid_prefix)) return false;
  const std::string pid_text = name.substr(pid_prefix.size());
  if (pid_text.empty() || pid_text.size() > 9 ||
      pid_text.find_first_not_of("0123456789") != std::string::npos)
    return false;
  const pid_t pid = static_cast<pid_t>(std::stol(pid_text));
  return pid != ::getpid() && ::kill(pid, 0) != 0 && errno == ESRCH;  // not alive, and ours to ask
}

}  // namespace

int RemoveDeadWorkersFolders(const fs::path& temp, const std::string& host) {
  const std::string any = DefaultWorkDir(temp, "").filename().string();
  const std::string pid_prefix = DefaultWorkDir(temp, host + "-").filename().string();
  int removed = 0;
  std::error_code error;
  for (auto it = fs::directory_iterator(temp, error); !error && it != fs::directory_iterator();
       it.increment(error)) {
    const std::string name = it->path().filename().string();
    if (!name.starts_with(any)) continue;
    struct stat info {};
    if (::lstat(it->path().c_str(), &info) != 0 || !S_ISDIR(info.st_mode) || info.st_uid != ::getuid())
      continue;
    if (!LeftByAWorkerGone(it->path(), name, pid_prefix)) continue;
    std::error_code ignored;
    if (fs::remove_all(it->path(), ignored) > 0) ++removed;
  }
  return removed;
}

bool RunLeasedJob(WorkerClient& client, const v1::LeaseResponse& lease, const Device& device,
                  const RunnerSettings& settings, WorkerMetrics& metrics,
                  const std::atomic<bool>& shutting_down) {
  const auto& job = lease.job();
  const JobFolder folder(settings.work_dir / job.id());
  const fs::path& job_dir = folder.path();
  spdlog::info(
      "[{}] job {} (attempt {}){}", device.name, job.id(), lease.attempt(),
      job.has_checkpoint() ? " resuming from checkpoint " + job.checkpoint().sha256().substr(0, 12) : "");
  auto& gauges = metrics.For(device.name);
  gauges.busy.Set(1);
  ProgressReporter reporter(client, lease.lease_id(), settings.heartbeat, settings.lease_ttl);
  // The job's reporting ends: heartbeats stop (the lease is then the server's to keep or expire).
  const auto stop_reporting = [&] {
    reporter.Stop();
    gauges.busy.Set(0);
  };
  int last_iteration = 0;
  bool disk_full = false;
  try {
    // A server restart mid-download is waited out while the lease is held, as the results' upload is
    // (it cost the job an attempt; found 2026-12-05); what arrived is kept and the rest resumed.
    WhileLeaseHeld(
        client, reporter, [&] { client.GetFiles(lease.lease_id(), job_dir / "clip", job.clip()); },
        &shutting_down);
    if (job.has_checkpoint() && !job.checkpoint().sha256().empty()) {
      v1::Manifest checkpoint;
      *checkpoint.add_files() = job.checkpoint();
      WhileLeaseHeld(
          client, reporter, [&] { client.GetFiles(lease.lease_id(), job_dir / "checkpoint", checkpoint); },
          &shutting_down);
    }
    fs::remove_all(job_dir / "out");
    auto options = OptionsFor(job, job_dir, device);
    // Issue 16: a job submitted as a raw stereo recording is prepared into out/clip/ first; issue 15:
    // a DICOM recording is converted into a clip (and its study is where the DICOM results go).
    std::optional<RecordingClip> recording;
    if (job.has_prepare()) {
      options.clip_dir = PrepareJobRecording(job, job_dir / "clip", job_dir / "out", reporter, [&] {
                           return shutting_down.load() || reporter.stop_requested().has_value();
                         }).string();
    } else {
      recording = PrepareRecording(options.clip_dir, job.recording(), job_dir / "clip-from-dicom");
      if (recording) options.clip_dir = recording->clip_dir.string();
      options.frames = ClipFolderFrames(recording, job.recording());
      // A clip folder's picked frames were cut by the CLI before the upload (client/clip_cut.h).
      options.frames_cut = !recording && !options.frames.SelectsAll();
    }
    // Results no call could hand back are refused before the training (a recording's frames are
    // known only now; a clip folder's the CLI checked).
    CheckResultsFit(ListClipFrames(options.clip_dir).size(), WritesUncertaintyMaps(options.config),
                    job.clip().ByteSizeLong(), options.clip_dir);

    ReconstructHooks hooks;
    hooks.progress_interval_s = std::min(2.0, std::chrono::duration<double>(settings.heartbeat).count());
    hooks.preview_interval_s = settings.preview_interval_s;
    hooks.checkpoint_interval_s = settings.checkpoint_interval_s;
    hooks.on_progress = [&](const Progress& p) {
      reporter.SetProgress(ToProto(p));
      if (!p.phase.empty()) return;  // evaluation: the training gauges keep their last values
      gauges.samples_per_second.Set(p.samples_per_second);
      gauges.psnr.Set(p.train_psnr);
      // A resumed run's checkpoint's iterations were counted by the worker that trained them.
      last_iteration = std::max(last_iteration, p.first_iteration);
      if (p.iteration > last_iteration) gauges.iterations.Increment(p.iteration - last_iteration);
      last_iteration = p.iteration;
      metrics.UpdateMemory();
    };
    hooks.on_preview = [&](const eval::Preview& preview) {
      reporter.AddPreview(EncodePreview(preview, last_iteration));
    };
    // A checkpoint only spares a job handed out again its training so far: it is retried while the
    // server answers the job's heartbeats (a wait for an upload slot too), and skipped, the job going
    // on, when the server's data disk is full or it has answered none for two heartbeats (at least
    // 5 s). Training waits meanwhile: 30 s of patience held a job past its budget while the server was
    // down (found 2026-12-07).
    const auto checkpoint_patience =
        std::max<std::chrono::milliseconds>(std::chrono::seconds(5), 2 * settings.heartbeat);
    WarningPacer checkpoint_warnings;
    hooks.on_checkpoint = [&](const std::string& path) {
      try {
        reporter.SetCheckpoint(WhileLeaseHeld(
            client, reporter, [&] { return UploadCheckpoint(client, path); }, nullptr, {},
            checkpoint_patience));
      } catch (const Error& e) {
        if (e.code() != ErrorCode::kUnavailable && !ServerDiskFull(e)) throw;
        // Training's end writes one more at once: the same line twice, 0.1 s apart (found 2026-12-07).
        if (int held = 0; checkpoint_warnings.Due(held)) {
          spdlog::warn("[{}] job {}: checkpoint not uploaded ({}); the job goes on{}", device.name, job.id(),
                       e.what(),
                       held > 0 ? fmt::format(" ({} more not uploaded since the last warning)", held) : "");
        }
      }
    };
    hooks.should_stop = [&] { return shutting_down.load() || reporter.stop_requested().has_value(); };

    const auto summary = Reconstruct(options, hooks);
    if (const auto stop = reporter.stop_requested()) {
      stop_reporting();
      spdlog::info("[{}] job {} stopped: {}", device.name, job.id(), v1::ProgressReply::Action_Name(*stop));
    } else if (summary.cancelled) {
      stop_reporting();
      Tell(client, lease.lease_id(), "shutting down (handed back)", true, true);
    } else {
      // The heartbeats go on while the results are written and uploaded, so the lease holds however
      // long that takes (a slow link, or the server's upload slots all taken by clients' uploads).
      // They ended with the reconstruction once: a wait longer than the lease's time handed the job
      // out again and the finished results were refused.
      WriteJobDicom(options.out_dir, recording, job.dicom());
      v1::CompleteRequest complete;
      complete.set_lease_id(lease.lease_id());
      *complete.mutable_result() = ManifestOfDirectory(options.out_dir);
      v1::Progress uploading;
      uploading.set_phase("upload");
      uploading.set_total_iterations(complete.result().files_size());
      reporter.SetProgress(uploading);
      // While the server's full disk refuses them, `status` says the results wait for its space.
      v1::Progress waiting = uploading;
      waiting.set_phase("upload-wait");
      WhileLeaseHeld(
          client, reporter,
          [&] {
            reporter.SetProgress(uploading);
            client.PutFiles(options.out_dir, complete.result());
          },
          &shutting_down, [&] { reporter.SetProgress(waiting); });
      stop_reporting();
      complete.set_summary_json(SummaryJson(summary));
      WhileUnavailable(client, [&] { return client.CompleteWithResults(options.out_dir, complete); });
      spdlog::info("[{}] job {} done: {} iterations, {} result file(s)", device.name, job.id(),
                   summary.iterations, complete.result().files_size());
    }
  } catch (const Error& e) {
    stop_reporting();
    spdlog::error("[{}] job {}: {}: {}", device.name, job.id(), ErrorCodeName(e.code()), e.what());
    // A write the disk refused (its message carries the system's words for ENOSPC or EDQUOT; the
    // file written in part may already be gone), or any failure while the scratch folder is full (an
    // image codec reports a full disk as a failed write): the disk's fault, the job goes back uncounted.
    const std::int64_t free_bytes = ScratchFree(settings.work_dir);
    const std::string_view message = e.what();
    disk_full = (free_bytes >= 0 && free_bytes < settings.min_free_bytes) ||
                message.find(std::strerror(ENOSPC)) != std::string_view::npos ||
                message.find(std::strerror(EDQUOT)) != std::string_view::npos;
    if (!reporter.stop_requested()) {
      const bool bad_input = e.code() == ErrorCode::kInvalidArgument && !disk_full;
      // A shutdown's stop, wherever it met the job (loading the clip, evaluating), says it as a stop
      // in training does: "CANCELLED: the clip-from-dicom: the clip's load was stopped" named a scratch
      // folder (found 2026-12-07); the worker's log has where it was.
      const bool handed_back = e.code() == ErrorCode::kCancelled && shutting_down.load() && !disk_full;
      const std::string reason =
          handed_back ? "shutting down (handed back)"
          : disk_full
              ? "worker " + client.worker_id() + ": its scratch folder " + settings.work_dir.string() +
                    " ran out of space (" + std::to_string(free_bytes) + " bytes free now, needs " +
                    std::to_string(settings.min_free_bytes) + " to take a job): " + e.what()
              : std::string(ErrorCodeName(e.code())) + ": " +
                    InTheClip(InTheUsersNames(e.what(), job, job_dir / "clip"), job_dir);
      // Issue 16: stopped by a shutdown while preparing: handed back without counting an attempt; so
      // are results the server's full disk refused (a shutdown while they waited: not the job's fault).
      Tell(client, lease.lease_id(), reason, !bad_input,
           e.code() == ErrorCode::kCancelled || disk_full || ServerDiskFull(e));
    }
  } catch (const std::exception& e) {
    stop_reporting();
    spdlog::error("[{}] job {}: {}", device.name, job.id(), e.what());
    if (!reporter.stop_requested()) Tell(client, lease.lease_id(), e.what(), true, false);
  }
  return disk_full;
}

}  // namespace endorecon::worker
