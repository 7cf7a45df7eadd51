// --exit-when-idle: a worker that has had no job on any of its devices for this long leaves, so that
// an allocation of a batch system (Slurm) is given back rather than held, idle, to its time limit (a
// queue empty for an hour held four GPUs for the script's 24 hours; found 2026-12-07). Time spent
// unable to reach the server, or refused by it, counts as idle too; the exit status then says so
// (kIdleUnreachableExit), so that the allocation shows as failed; so does time spent with no room in
// the scratch folder to take a job (kIdleScratchFullExit: the queue was not even asked, and exit 0
// would say it was empty). Thread-safe.
#pragma once

#include <chrono>
#include <mutex>

namespace endorecon::worker {

// EX_UNAVAILABLE: the worker left idle because it could not reach the server or was refused.
inline constexpr int kIdleUnreachableExit = 69;
// EX_TEMPFAIL: the worker left idle because its scratch folder had no room to take a job
// (--min-free-bytes); a job may have waited in the queue all along.
inline constexpr int kIdleScratchFullExit = 75;

class IdleWatch {
 public:
  using Clock = std::chrono::steady_clock;
  // `limit` 0: never idle.
  IdleWatch(std::chrono::milliseconds limit, Clock::time_point now);
  std::chrono::milliseconds limit() const { return limit_; }

  // A device took a job / finished it (handed back, failed or done).
  void JobStarted();
  void JobEnded(Clock::time_point now);
  // How the latest call to the server went: answered (a job or none) or failed.
  void ServerAnswered(bool answered);
  // True once no device has run a job for the limit.
  bool Due(Clock::time_point now) const;
  // How long until Due, at most `most` (`most` while a job runs or without a limit): a lease's
  // long poll waits no longer, so the worker leaves on time (it left at the poll's end, 10 s for 3).
  std::chrono::milliseconds Left(Clock::time_point now, std::chrono::milliseconds most) const;
  // Whether the scratch folder has room to take a job, as last seen.
  void ScratchFull(bool full);
  // Whether the latest call to the server failed.
  bool ServerFailing() const;
  // Whether the scratch folder had no room, as last seen.
  bool ScratchWasFull() const;
  // The worker leaves for being idle.
  void Leave();
  // The worker's exit status when it left idle: kIdleScratchFullExit while its scratch folder had no
  // room, kIdleUnreachableExit while the server failed, else 0.
  int ExitCode() const;

 private:
  const std::chrono::milliseconds limit_;
  mutable std::mutex mutex_;
  int running_ = 0;
  Clock::time_point idle_since_;
  bool server_failing_ = false;
  bool scratch_full_ = false;
  bool left_ = false;
};

}  // namespace endorecon::worker
