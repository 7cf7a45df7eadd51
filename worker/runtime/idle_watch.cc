#include "worker/runtime/idle_watch.h"

#include <algorithm>

namespace endorecon::worker {

IdleWatch::IdleWatch(std::chrono::milliseconds limit, Clock::time_point now)
    : limit_(limit), idle_since_(now) {}

void IdleWatch::JobStarted() {
  std::lock_guard lock(mutex_);
  ++running_;
}

void IdleWatch::JobEnded(Clock::time_point now) {
  std::lock_guard lock(mutex_);
  if (--running_ == 0) idle_since_ = now;
}

void IdleWatch::ServerAnswered(bool answered) {
  std::lock_guard lock(mutex_);
  server_failing_ = !answered;
}

bool IdleWatch::Due(Clock::time_point now) const {
  std::lock_guard lock(mutex_);
  return limit_.count() > 0 && running_ == 0 && now - idle_since_ >= limit_;
}

std::chrono::milliseconds IdleWatch::Left(Clock::time_point now, std::chrono::milliseconds most) const {
  std::lock_guard lock(mutex_);
  if (limit_.count() <= 0 || running_ > 0) return most;
  const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(idle_since_ + limit_ - now);
  return std::clamp(left, std::chrono::milliseconds(0), most);
}

void IdleWatch::ScratchFull(bool full) {
  std::lock_guard lock(mutex_);
  scratch_full_ = full;
}

bool IdleWatch::ScratchWasFull() const {
  std::lock_guard lock(mutex_);
  return scratch_full_;
}

bool IdleWatch::ServerFailing() const {
  std::lock_guard lock(mutex_);
  return server_failing_;
}

void IdleWatch::Leave() {
  std::lock_guard lock(mutex_);
  left_ = true;
}

int IdleWatch::ExitCode() const {
  std::lock_guard lock(mutex_);
  if (!left_) return 0;
  return scratch_full_ ? kIdleScratchFullExit : server_failing_ ? kIdleUnreachableExit : 0;
}

}  // namespace endorecon::worker
