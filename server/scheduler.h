// The queue of runnable jobs, in memory (rebuilt from the JobStore at start): highest priority
// first, then oldest (lowest sequence number). Workers long-poll it. Thread-safe.
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <map>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <tuple>

namespace endorecon::server {

class Scheduler {
 public:
  // Queues `job_id` of `tenant` (again, if it was queued before: the old entry is replaced).
  void Push(const std::string& job_id, int priority, std::int64_t seq, const std::string& tenant = "");
  // Removes a queued job; false if it was not queued.
  bool Remove(const std::string& job_id);
  // The next job, waiting until `deadline` for one; nullopt on timeout or after Shutdown(). With
  // `tenant`, the next job of that tenant (a worker whose token serves one tenant), the others left
  // queued in their order.
  std::optional<std::string> PopWait(std::chrono::steady_clock::time_point deadline,
                                     const std::optional<std::string>& tenant = std::nullopt);
  std::size_t Depth() const;
  // Wakes every waiter for good.
  void Shutdown();

 private:
  using Key = std::tuple<int, std::int64_t, std::string>;  // (-priority, seq, id)
  struct Queued {
    Key key;
    std::string tenant;
  };
  // The first queued job `tenant` may take; queue_.end() when none.
  std::set<Key>::iterator FirstFor(const std::optional<std::string>& tenant);

  mutable std::mutex mutex_;
  std::condition_variable ready_;
  std::set<Key> queue_;
  std::map<std::string, Queued> jobs_;
  bool shutdown_ = false;
};

}  // namespace endorecon::server
