// The durable record of every job: one SQLite database in WAL mode with synchronous=FULL. Each row
// keeps the whole v1::Job (serialized) plus the columns the queries need (state, priority, tenant
// and the bytes the job keeps stored, for quotas). Thread-safe.
//
// Group commit: Insert and Update only stage a write (in memory; Get sees it at once) and Flush
// makes every write staged before it durable. Writes staged by many threads while one commit's
// fsync runs go to disk together in the next transaction, so a hundred callers wait for about two
// fsyncs, not for a hundred in a row. A caller answers only after its Flush: a write that was
// acknowledged survives a kill -9 of the server and a power cut. Pages (List) and the queries
// behind quotas, recovery and retention read what is committed (the last three flush first). Get
// and List go through a second connection, so in WAL mode they never wait behind a write's fsync.
// The log is checkpointed on a thread of its own (WalCheckpointer), not inside a commit.
//
// A commit the database refuses (an I/O error, a full disk) rolls its batch back and breaks the
// store: what the server holds in memory may then be ahead of the disk, so every later write and
// Flush throws Error(kUnavailable) and the server must restart (it recovers from the disk, which
// holds exactly what was acknowledged).
#pragma once

#include <sqlite3.h>

#include <condition_variable>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "endorecon/v1/job.pb.h"
#include "server/wal_checkpointer.h"

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

  // Stages a new job (its id must be new: kInternal otherwise); returns its sequence number.
  std::int64_t Insert(const v1::Job& job);
  // Stages the replacement of a job by id. Throws kNotFound if there is none.
  void Update(const v1::Job& job);
  // Returns once every write staged before the call is committed (see above). Throws
  // Error(kUnavailable) naming the file when the commit failed or the store is broken.
  void Flush();
  // The job as last written, staged or committed.
  std::optional<StoredJob> Get(const std::string& id);

  struct Page {
    std::vector<v1::Job> jobs;
    std::int64_t next_before_seq = 0;  // 0: no more
  };
  // Committed jobs newest first, restricted to `states` (empty: all) and to `tenant` when given, with
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
  // True when a write transaction succeeds and no commit has failed (readiness).
  bool Writable();
  // True once a commit has failed (see above).
  bool Broken();

  // Called after every successful commit, by the committing thread outside the store's locks, with
  // the commit's duration (the transaction and its fsyncs) and the writes it carried: the server's
  // metrics and its slow-commit log. Set it before the store is shared between threads.
  using CommitObserver = std::function<void(double seconds, std::size_t writes)>;
  void SetCommitObserver(CommitObserver observer) { observer_ = std::move(observer); }

 private:
  // A job's latest write not yet committed (several writes of one job between commits are one row
  // write at the next).
  struct Staged {
    std::int64_t seq = 0;
    v1::Job job;
    std::uint64_t write = 0;  // its number among all staged writes
    bool insert = false;      // the job has no row yet
  };
  // The seq of a committed job, or 0.
  std::int64_t CommittedSeq(const std::string& id);
  void StageLocked(std::int64_t seq, bool insert, const v1::Job& job);
  // Writes `batch` in one transaction; throws (after rolling back) when the database refuses.
  void Commit(const std::vector<Staged>& batch);
  void ThrowIfBroken() const;

  std::filesystem::path file_;
  sqlite3* db_ = nullptr;  // writes, and the reads that follow a Flush
  std::mutex mutex_;
  sqlite3* reader_ = nullptr;  // Get of committed jobs and List: sees every committed write
  std::mutex read_mutex_;
  std::unique_ptr<WalCheckpointer> checkpointer_;  // db_'s checkpoints

  std::mutex staged_mutex_;  // guards everything below
  std::condition_variable committed_;
  std::unordered_map<std::string, Staged> staged_;  // by id: what the next commit writes
  std::uint64_t writes_staged_ = 0;
  std::uint64_t writes_durable_ = 0;
  bool committing_ = false;
  std::int64_t next_seq_ = 1;
  std::string broken_;  // why the store is broken; empty while it is not
  CommitObserver observer_;
};

// The bytes `job` keeps in the blob store (clip, result, checkpoint; 0 once expired), counted per
// job even where jobs share content: a tenant's quota is what its own jobs would need alone.
std::int64_t StoredBytes(const v1::Job& job);

}  // namespace endorecon::server
