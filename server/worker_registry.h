// The workers the server has heard from: any worker call (Register, Lease, Report) counts as a
// sign of life, so workers need not re-register after a server restart. In memory, but for the drains,
// which are kept in a file (server/drain_file.h) across restarts. Thread-safe.
#pragma once

#include <chrono>
#include <filesystem>
#include <map>
#include <mutex>
#include <set>
#include <string>
#include <vector>

#include "endorecon/v1/job_service.pb.h"
#include "endorecon/v1/worker_service.pb.h"

namespace endorecon::server {

class WorkerRegistry {
 public:
  // A worker counts as alive (connected) for `alive_window` after its last call.
  // `drains_file`: where the drains are kept ("": in memory only). The workers it names are listed as
  // draining (and not alive) from the start; a file that cannot be read is warned of and left aside.
  explicit WorkerRegistry(std::chrono::milliseconds alive_window, std::filesystem::path drains_file = {});

  // Records the worker's host and devices (names and what they are) from its registration, and the
  // token (its label, `principal`) it registered with. Returns the label of the token the id was
  // registered and alive with when that was another ("" otherwise), for the caller to log: a token
  // rotated, or a second worker claiming the id (which merged with the first in `workers` and undid
  // its drain; found 2026-12-06). Neither is refused: the server cannot tell them apart.
  // `tenant` is the one tenant whose jobs its token serves ("": every tenant's), listed with it.
  std::string Register(const v1::RegisterRequest& request, const std::string& principal = "",
                       const std::string& tenant = "");
  // Whether `worker_id` registered with this server (a worker only seen leasing did not).
  bool Registered(const std::string& worker_id) const;
  void Touch(const std::string& worker_id);
  // A call of `worker_id` carried the token labelled `principal`, which serves `tenant` ("": every
  // tenant): lists the worker with that tenant, and when it registered with another token, records
  // this one and returns the other's label (for the caller to log), else "".
  std::string NoteToken(const std::string& worker_id, const std::string& principal,
                        const std::string& tenant = "");
  // The worker said it is stopping: not alive from now (listed until forgotten, as a silent one).
  void Leave(const std::string& worker_id);
  // Marks a worker draining (or not): Draining says so until undone or until it registers anew (a
  // restarted worker serves again; a registration that answers register_again, RegisterRequest.again,
  // is the same process after a server restart and keeps its drain). Throws Error(kNotFound) for a
  // worker never heard from, and as WriteDrains when the drains file cannot be written.
  v1::WorkerInfo SetDraining(const std::string& worker_id, bool draining);
  bool Draining(const std::string& worker_id) const;
  void AddJob(const std::string& worker_id, const std::string& job_id);
  void RemoveJob(const std::string& worker_id, const std::string& job_id);
  std::vector<v1::WorkerInfo> List() const;
  int CountAlive() const;
  // Forgets the workers last seen before `cutoff` that hold no job (a worker's default id is
  // host-pid, so every restart added one for good). Returns how many.
  std::size_t Forget(std::chrono::steady_clock::time_point cutoff);

 private:
  struct Entry {
    v1::WorkerInfo info;
    std::set<std::string> jobs;
    std::chrono::steady_clock::time_point last_seen;
    // Whether it registered with this server (a worker only seen leasing, after a restart, did not)
    // and the label of the token it did so with.
    bool registered = false;
    std::string principal;
    // It said it leaves (Leave): a lease call of its still on the way is no sign of life. One that
    // reached the server after the Leave listed a stopped worker alive (CI, 2026-12-07). Register
    // ends it.
    bool left = false;
  };
  Entry& At(const std::string& worker_id);
  // A last-seen time just outside the alive window: listed as not alive from now.
  std::chrono::steady_clock::time_point NotAliveSince() const {
    return std::chrono::steady_clock::now() - alive_window_ - std::chrono::milliseconds(1);
  }
  // Writes the drains file (under mutex_). Throws as WriteDrains.
  void SaveDrains() const;
  // The same, but warns instead of throwing: for changes the caller did not ask for.
  void SaveDrainsOrWarn() const;
  // What List shows of `entry` at `now` (alive, and its jobs).
  v1::WorkerInfo InfoOf(const Entry& entry, std::chrono::steady_clock::time_point now) const;

  std::chrono::milliseconds alive_window_;
  std::filesystem::path drains_file_;
  mutable std::mutex mutex_;
  std::map<std::string, Entry> workers_;
};

}  // namespace endorecon::server
