// Work that falls due at given times, done one item at a time in a thread of its own: the DICOM
// retrievals and sends, each retried after a wait. An item is a key (a job, or a job and a PACS);
// a key already waiting is not added again.
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <map>
#include <mutex>
#include <thread>
#include <utility>

#include "server/unix_time.h"

namespace endorecon::server {

template <typename Key>
class DueQueue {
 public:
  // `run` does one item, and throws nothing (it runs in the queue's thread).
  explicit DueQueue(std::function<void(const Key&)> run) : run_(std::move(run)), thread_([this] { Loop(); }) {}
  // Stops after the item in progress and joins the thread.
  ~DueQueue() {
    {
      std::lock_guard lock(mutex_);
      stopping_ = true;
    }
    wake_.notify_all();
    thread_.join();
  }
  DueQueue(const DueQueue&) = delete;
  DueQueue& operator=(const DueQueue&) = delete;

  // Runs `key` at `at_unix_ms` (0 or past: as soon as the items before it are done).
  void Schedule(const Key& key, std::int64_t at_unix_ms) {
    {
      std::lock_guard lock(mutex_);
      for (const auto& [at, queued] : due_) {
        if (queued == key) return;
      }
      due_.emplace(at_unix_ms, key);
    }
    wake_.notify_all();
  }

 private:
  void Loop() {
    std::unique_lock lock(mutex_);
    while (!stopping_) {
      if (due_.empty()) {
        wake_.wait(lock);
        continue;
      }
      const auto first = due_.begin();
      const std::int64_t wait_ms = first->first - NowUnixMs();
      if (wait_ms > 0) {
        wake_.wait_for(lock, std::chrono::milliseconds(wait_ms));
        continue;
      }
      const Key key = first->second;
      due_.erase(first);
      lock.unlock();
      run_(key);
      lock.lock();
    }
  }

  std::function<void(const Key&)> run_;
  std::mutex mutex_;
  std::condition_variable wake_;
  std::multimap<std::int64_t, Key> due_;  // by the Unix ms each falls due
  bool stopping_ = false;
  std::thread thread_;
};

}  // namespace endorecon::server
