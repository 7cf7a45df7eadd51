#include "server/scheduler.h"

namespace endorecon::server {

void Scheduler::Push(const std::string& job_id, int priority, std::int64_t seq) {
  {
    std::lock_guard lock(mutex_);
    if (const auto old = keys_.find(job_id); old != keys_.end()) queue_.erase(old->second);
    Key key{-priority, seq, job_id};
    queue_.insert(key);
    keys_[job_id] = key;
  }
  ready_.notify_one();
}

bool Scheduler::Remove(const std::string& job_id) {
  std::lock_guard lock(mutex_);
  const auto found = keys_.find(job_id);
  if (found == keys_.end()) return false;
  queue_.erase(found->second);
  keys_.erase(found);
  return true;
}

std::optional<std::string> Scheduler::PopWait(std::chrono::steady_clock::time_point deadline) {
  std::unique_lock lock(mutex_);
  if (!ready_.wait_until(lock, deadline, [&] { return shutdown_ || !queue_.empty(); }) || shutdown_) {
    return std::nullopt;
  }
  const Key next = *queue_.begin();
  queue_.erase(queue_.begin());
  keys_.erase(std::get<2>(next));
  return std::get<2>(next);
}

std::size_t Scheduler::Depth() const {
  std::lock_guard lock(mutex_);
  return queue_.size();
}

void Scheduler::Shutdown() {
  {
    std::lock_guard lock(mutex_);
    shutdown_ = true;
  }
  ready_.notify_all();
}

}  // namespace endorecon::server
