#include "server/scheduler.h"

namespace endorecon::server {

void Scheduler::Push(const std::string& job_id, int priority, std::int64_t seq, const std::string& tenant) {
  {
    std::lock_guard lock(mutex_);
    if (const auto old = jobs_.find(job_id); old != jobs_.end()) queue_.erase(old->second.key);
    Key key{-priority, seq, job_id};
    queue_.insert(key);
    jobs_[job_id] = {key, tenant};
  }
  // Every waiter: one that serves another tenant would take the wake-up and leave this job queued.
  ready_.notify_all();
}

bool Scheduler::Remove(const std::string& job_id) {
  std::lock_guard lock(mutex_);
  const auto found = jobs_.find(job_id);
  if (found == jobs_.end()) return false;
  queue_.erase(found->second.key);
  jobs_.erase(found);
  return true;
}

std::set<Scheduler::Key>::iterator Scheduler::FirstFor(const std::optional<std::string>& tenant) {
  if (!tenant) return queue_.begin();
  // A walk in queue order: a queue is hundreds of jobs at most, and workers of one tenant are few.
  for (auto it = queue_.begin(); it != queue_.end(); ++it) {
    if (jobs_.at(std::get<2>(*it)).tenant == *tenant) return it;
  }
  return queue_.end();
}

std::optional<std::string> Scheduler::PopWait(std::chrono::steady_clock::time_point deadline,
                                              const std::optional<std::string>& tenant) {
  std::unique_lock lock(mutex_);
  if (!ready_.wait_until(lock, deadline, [&] { return shutdown_ || FirstFor(tenant) != queue_.end(); }) ||
      shutdown_) {
    return std::nullopt;
  }
  const auto next = FirstFor(tenant);
  const std::string id = std::get<2>(*next);
  queue_.erase(next);
  jobs_.erase(id);
  return id;
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
