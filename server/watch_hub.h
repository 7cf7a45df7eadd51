// What watchers of a job see: the latest job snapshot, progress and preview of each kind, each
// with the version at which it was published. A watcher asks for what changed since the version
// it saw last, so a slow watcher skips stale progress instead of queueing it (memory stays bounded
// however many watchers there are). In memory. Thread-safe. Versions grow across all jobs, so a
// job's entry can be dropped (Prune, once the job has settled) and made again without a watcher's
// `seen` hiding what the new one holds.
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "endorecon/v1/job.pb.h"

namespace endorecon::server {

class WatchHub {
 public:
  struct Changes {
    std::uint64_t version = 0;  // pass back as `seen` to the next Wait
    std::optional<v1::Job> job;
    std::optional<v1::Progress> progress;
    std::vector<v1::Preview> previews;
  };

  void PublishJob(const v1::Job& job);  // a terminal job's previews are dropped
  void PublishProgress(const std::string& job_id, const v1::Progress& progress);
  void PublishPreview(const std::string& job_id, const v1::Preview& preview);
  // Returns what was published for `job_id` after version `seen`, waiting until `deadline` for
  // something (an empty Changes on timeout or after Shutdown()).
  Changes Wait(const std::string& job_id, std::uint64_t seen, std::chrono::steady_clock::time_point deadline);
  void Shutdown();
  // Drops the entries nobody is waiting on of jobs that settled (finished, no DICOM send waiting)
  // at least `grace` before `now`, and the empty ones a Wait made; returns how many. Without it
  // the hub kept every job the server ever ran (bench/service_load). A watcher of a dropped job
  // finds it settled in the job store.
  std::size_t Prune(std::chrono::steady_clock::time_point now, std::chrono::seconds grace);
  std::size_t Size();

 private:
  template <typename T>
  struct Versioned {
    // No default member initializer: clang 14 cannot compile reads of one in a nested template
    // ("cannot compile this scalar expression yet"); value-initialisation zeroes it all the same.
    std::uint64_t version;
    T value;
  };
  struct Entry {
    std::mutex mutex;
    std::condition_variable changed;
    std::uint64_t version = 0;
    std::optional<Versioned<v1::Job>> job;
    std::optional<Versioned<v1::Progress>> progress;
    std::map<std::string, Versioned<v1::Preview>> previews;  // by kind
    // Read by Prune without the entry's mutex (Wait takes the hub's mutex under it).
    std::atomic<bool> published{false};
    std::atomic<std::int64_t> settled_ns{0};  // steady_clock; 0: not settled
  };
  std::shared_ptr<Entry> EntryOf(const std::string& job_id);
  template <typename Update>
  void Publish(const std::string& job_id, Update&& update);

  std::mutex mutex_;
  std::map<std::string, std::shared_ptr<Entry>> entries_;
  std::atomic<std::uint64_t> last_version_{0};
  bool shutdown_ = false;
};

}  // namespace endorecon::server
