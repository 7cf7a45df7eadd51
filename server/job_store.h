// The durable record of every job: one SQLite database in WAL mode with synchronous=FULL, so a
// job is on disk when Insert/Update return and survives a kill -9 of the server. Each row keeps
// the whole v1::Job (serialized) plus the columns the queries need. Thread-safe.
#pragma once

#include <sqlite3.h>

#include <cstdint>
#include <filesystem>
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
  // Jobs newest first, restricted to `states` (empty: all), with seq < before_seq (0: from the newest).
  Page List(const std::vector<v1::JobState>& states, int limit, std::int64_t before_seq);
  // Every QUEUED or RUNNING job, oldest first (what the scheduler and leases rebuild from).
  std::vector<StoredJob> Unfinished();
  std::map<v1::JobState, std::int64_t> CountByState();
  // True when a write transaction succeeds (readiness).
  bool Writable();

 private:
  sqlite3* db_ = nullptr;
  std::mutex mutex_;
};

}  // namespace endorecon::server
