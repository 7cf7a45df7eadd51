#include "server/stall_watch.h"

#include <spdlog/spdlog.h>

namespace endorecon::server {

StallWatch::StallWatch(std::chrono::milliseconds limit) : limit_(limit), thread_([this] { Loop(); }) {}

StallWatch::~StallWatch() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  changed_.notify_all();
  thread_.join();
}

bool StallWatch::Guard(grpc::ServerContext* context, const std::function<bool()>& operation) {
  std::uint64_t id;
  {
    std::lock_guard lock(mutex_);
    id = next_++;
    armed_[id] = {context, Clock::now() + limit_};
  }
  changed_.notify_all();
  const bool done = operation();
  std::lock_guard lock(mutex_);
  armed_.erase(id);
  return done;
}

std::uint64_t StallWatch::cancelled() const {
  std::lock_guard lock(mutex_);
  return cancelled_;
}

void StallWatch::Loop() {
  std::unique_lock lock(mutex_);
  while (!stopping_) {
    // Operations are armed in order and all with the same limit: the first is the next to expire.
    if (armed_.empty()) {
      changed_.wait(lock);
      continue;
    }
    auto first = armed_.begin();
    // A copy: wait_until reads its deadline again after waking, when the operation may have returned
    // and erased the entry (AddressSanitizer found the read of the freed node).
    const Clock::time_point deadline = first->second.deadline;
    if (Clock::now() < deadline) {
      changed_.wait_until(lock, deadline);
      continue;
    }
    grpc::ServerContext* context = first->second.context;
    armed_.erase(first);
    ++cancelled_;
    spdlog::warn("a stream to {} took no data for {} ms: cancelled", context->peer(), limit_.count());
    context->TryCancel();
  }
}

}  // namespace endorecon::server
