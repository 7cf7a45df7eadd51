// The durable record of every job: one SQLite database in WAL mode with synchronous=FULL, so a
// job is on disk when Insert/Update return and survives a kill -9 of the server. Each row keeps
// the whole v1::Job (serialized) plus the columns the queries need (state, priority, tenant and the
// bytes the job keeps stored, for quotas). Thread-safe. Reads of one job or one page (Get, List)
// go through a second connection, so in WAL mode they never wait behind a write's fsync.
#pragma once

#include <sqlite3.h>

#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "endorecon/v1/job.pb.h"

namespace endorecon::server {

// A job with its insertion sequence number (ages in the queue compare by it).
struct StoredJob {
  std::int64_t seq = 0;
  v1::Job job;
};

class JobStore {
 public:
  // Opens or creates the database. Throws Error(kUnavailable) naming the file if it cannot.
  explicit JobStore(const std::filesystem::path& db_file);
  ~JobStore();
  JobStore(const JobStore&) = delete;
  JobStore& operator=(const JobStore&) = delete;

  // Adds a new job (its id must be new); returns its sequence number.
  std::int64_t Insert(const v1::Job& job);
  // Replaces a stored job by id. Throws kNotFound if there is none.
  void Update(const v1::Job& job);
  std::optional<StoredJob> Get(const std::string& id);

  struct Page {
    std::vector<v1::Job> jobs;
    std::int64_t next_before_seq = 0;  // 0: no more
  };
  // Jobs newest first, restricted to `states` (empty: all) and to `tenant` when given, with
  // seq < before_seq (0: from the newest).
  Page List(const std::vector<v1::JobState>& states, int limit, std::int64_t before_seq,
            const std::optional<std::string>& tenant = std::nullopt);
  // Every QUEUED or RUNNING job, oldest first (what the scheduler and leases rebuild from).
  std::vector<StoredJob> Unfinished();
  std::map<v1::JobState, std::int64_t> CountByState();

  // What one tenant holds: its QUEUED and RUNNING jobs, and the bytes its jobs keep (StoredBytes).
  struct Usage {
    std::int64_t active_jobs = 0;
    std::int64_t bytes = 0;
  };
  Usage UsageOf(const std::string& tenant);
  // Calls `visit` for every job, oldest first (retention's view of what references which blob).
  void Scan(const std::function<void(const StoredJob&)>& visit);
  // True when a write transaction succeeds (readiness).
  bool Writable();

 private:
  sqlite3* db_ = nullptr;  // writes, and the reads writers depend on
  std::mutex mutex_;
  sqlite3* reader_ = nullptr;  // Get and List: sees every committed write
  std::mutex read_mutex_;
};

// The bytes `job` keeps in the blob store (clip, result, checkpoint; 0 once expired), counted per
// job even where jobs share content: a tenant's quota is what its own jobs would need alone.
std::int64_t StoredBytes(const v1::Job& job);

}  // namespace endorecon::server
