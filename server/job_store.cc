#include "server/job_store.h"

#include <spdlog/spdlog.h>

#include <chrono>

#include "common/error.h"
#include "common/manifest.h"
#include "server/sqlite_statement.h"

namespace endorecon::server {
namespace {

constexpr const char* kStore = "job store";

v1::Job Parse(const std::string& bytes, std::int64_t seq) {
  v1::Job job;
  if (!job.ParseFromString(bytes))
    Fail(ErrorCode::kDataLoss, "job store: row " + std::to_string(seq) + " is corrupt");
  return job;
}

bool HasColumn(sqlite3* db, const std::string& column) {
  Statement info(db, "PRAGMA table_info(jobs)", kStore);
  while (info.Step()) {
    if (info.Text(1) == column) return true;
  }
  return false;
}

// Stores made before tenants and quotas get the two columns, filled from the jobs themselves.
void AddAccessColumns(sqlite3* db) {
  if (HasColumn(db, "tenant")) return;
  Exec(db, "BEGIN IMMEDIATE", kStore);
  try {
    Exec(db, "ALTER TABLE jobs ADD COLUMN tenant TEXT NOT NULL DEFAULT ''", kStore);
    Exec(db, "ALTER TABLE jobs ADD COLUMN bytes INTEGER NOT NULL DEFAULT 0", kStore);
    std::vector<std::pair<std::int64_t, std::int64_t>> sizes;
    {
      Statement select(db, "SELECT seq, job FROM jobs", kStore);
      while (select.Step())
        sizes.emplace_back(select.Int(0), StoredBytes(Parse(select.Blob(1), select.Int(0))));
    }
    for (const auto& [seq, bytes] : sizes) {
      Statement update(db, "UPDATE jobs SET bytes = ? WHERE seq = ?", kStore);
      update.Bind(1, bytes);
      update.Bind(2, seq);
      update.Step();
    }
    Exec(db, "COMMIT", kStore);
  } catch (...) {
    sqlite3_exec(db, "ROLLBACK", nullptr, nullptr, nullptr);
    throw;
  }
}

}  // namespace

std::int64_t StoredBytes(const v1::Job& job) {
  if (job.expired_unix_ms() > 0) return 0;
  return TotalBytes(job.clip()) + TotalBytes(job.result()) + job.checkpoint().size();
}

JobStore::JobStore(const std::filesystem::path& db_file) : file_(db_file), db_(OpenStore(db_file, kStore)) {
  try {
    CheckDatabase(db_, db_file, kStore);
    Exec(db_,
         "CREATE TABLE IF NOT EXISTS jobs ("
         " seq INTEGER PRIMARY KEY AUTOINCREMENT,"
         " id TEXT NOT NULL UNIQUE,"
         " state INTEGER NOT NULL,"
         " priority INTEGER NOT NULL,"
         " job BLOB NOT NULL)",
         kStore);
    Exec(db_, "CREATE INDEX IF NOT EXISTS jobs_state ON jobs(state, seq)", kStore);
    AddAccessColumns(db_);
    Exec(db_, "CREATE INDEX IF NOT EXISTS jobs_tenant ON jobs(tenant, state)", kStore);
    // Staged inserts take their seq here, past every seq AUTOINCREMENT ever gave out.
    Statement last(db_,
                   "SELECT MAX(COALESCE((SELECT MAX(seq) FROM jobs), 0),"
                   " COALESCE((SELECT seq FROM sqlite_sequence WHERE name = 'jobs'), 0))",
                   kStore);
    last.Step();
    next_seq_ = last.Int(0) + 1;
    reader_ = OpenDatabase(db_file, kStore);
    checkpointer_ = std::make_unique<WalCheckpointer>(db_file, db_, kStore);
  } catch (...) {
    sqlite3_close(reader_);
    sqlite3_close(db_);
    throw;
  }
}

JobStore::~JobStore() {
  try {
    Flush();
  } catch (const Error& e) {
    spdlog::error("{}", e.what());
  }
  checkpointer_.reset();
  sqlite3_close(reader_);
  sqlite3_close(db_);
}

void JobStore::ThrowIfBroken() const {
  if (!broken_.empty()) Fail(ErrorCode::kUnavailable, broken_);
}

std::int64_t JobStore::CommittedSeq(const std::string& id) {
  std::lock_guard lock(read_mutex_);
  Statement select(reader_, "SELECT seq FROM jobs WHERE id = ?", kStore);
  select.BindText(1, id);
  return select.Step() ? select.Int(0) : 0;
}

void JobStore::StageLocked(std::int64_t seq, bool insert, const v1::Job& job) {
  ThrowIfBroken();
  staged_[job.id()] = Staged{seq, job, ++writes_staged_, insert};
}

std::int64_t JobStore::Insert(const v1::Job& job) {
  const bool committed = CommittedSeq(job.id()) != 0;
  std::lock_guard lock(staged_mutex_);
  if (committed || staged_.count(job.id()) > 0)
    Fail(ErrorCode::kInternal, "job store: job " + job.id() + " exists");
  const auto seq = next_seq_++;
  StageLocked(seq, true, job);
  return seq;
}

void JobStore::Update(const v1::Job& job) {
  {
    std::lock_guard lock(staged_mutex_);
    if (const auto found = staged_.find(job.id()); found != staged_.end()) {
      StageLocked(found->second.seq, found->second.insert, job);
      return;
    }
  }
  // Not staged: committed or nowhere. Its seq never changes, so asking outside the lock is safe.
  const auto seq = CommittedSeq(job.id());
  if (seq == 0) Fail(ErrorCode::kNotFound, "no job " + job.id());
  std::lock_guard lock(staged_mutex_);
  StageLocked(seq, false, job);
}

void JobStore::Flush() {
  std::unique_lock lock(staged_mutex_);
  const auto target = writes_staged_;
  while (writes_durable_ < target) {
    ThrowIfBroken();
    if (committing_) {
      committed_.wait(lock);
      continue;
    }
    // This thread commits everything staged so far, its own writes and those of the threads waiting.
    committing_ = true;
    std::vector<Staged> batch;
    batch.reserve(staged_.size());
    for (const auto& [id, staged] : staged_) batch.push_back(staged);
    const auto upto = writes_staged_;
    lock.unlock();
    std::string failure;
    const auto start = std::chrono::steady_clock::now();
    try {
      Commit(batch);
    } catch (const Error& e) {
      failure = e.what();
    }
    if (failure.empty() && observer_) {
      observer_(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(),
                batch.size());
    }
    lock.lock();
    committing_ = false;
    if (failure.empty()) {
      writes_durable_ = upto;
      // A job written again meanwhile stays staged, now with its row.
      for (const auto& written : batch) {
        const auto found = staged_.find(written.job.id());
        if (found->second.write <= upto) {
          staged_.erase(found);
        } else {
          found->second.insert = false;
        }
      }
    } else {
      broken_ = "job store " + file_.string() + ": a commit of " + std::to_string(batch.size()) +
                " write(s) failed (" + failure + "); the server must restart to recover from the disk" +
                (failure.find("its disk is full") != std::string::npos
                     ? ", and free space on it first: a restart alone meets the same full disk"
                     : "");
      spdlog::critical("{}", broken_);
    }
    committed_.notify_all();
  }
}

void JobStore::Commit(const std::vector<Staged>& batch) {
  std::lock_guard lock(mutex_);
  Exec(db_, "BEGIN IMMEDIATE", kStore);
  try {
    Statement insert(
        db_, "INSERT INTO jobs(seq, id, state, priority, tenant, bytes, job) VALUES(?, ?, ?, ?, ?, ?, ?)",
        kStore);
    Statement update(db_, "UPDATE jobs SET state = ?, priority = ?, bytes = ?, job = ? WHERE seq = ?",
                     kStore);
    for (const auto& staged : batch) {
      const auto& job = staged.job;
      if (staged.insert) {
        insert.Reset();
        insert.Bind(1, staged.seq);
        insert.BindText(2, job.id());
        insert.Bind(3, job.state());
        insert.Bind(4, job.priority());
        insert.BindText(5, job.tenant());
        insert.Bind(6, StoredBytes(job));
        insert.Bind(7, job.SerializeAsString());
        insert.Step();
      } else {
        update.Reset();
        update.Bind(1, job.state());
        update.Bind(2, job.priority());
        update.Bind(3, StoredBytes(job));
        update.Bind(4, job.SerializeAsString());
        update.Bind(5, staged.seq);
        update.Step();
      }
    }
    Exec(db_, "COMMIT", kStore);
  } catch (...) {
    sqlite3_exec(db_, "ROLLBACK", nullptr, nullptr, nullptr);
    throw;
  }
}

std::optional<StoredJob> JobStore::Get(const std::string& id) {
  {
    std::lock_guard lock(staged_mutex_);
    if (const auto found = staged_.find(id); found != staged_.end())
      return StoredJob{found->second.seq, found->second.job};
  }
  std::lock_guard lock(read_mutex_);
  Statement select(reader_, "SELECT seq, job FROM jobs WHERE id = ?", kStore);
  select.BindText(1, id);
  if (!select.Step()) return std::nullopt;
  return StoredJob{select.Int(0), Parse(select.Blob(1), select.Int(0))};
}

JobStore::Page JobStore::List(const std::vector<v1::JobState>& states, int limit, std::int64_t before_seq,
                              const std::optional<std::string>& tenant) {
  std::string sql = "SELECT seq, job FROM jobs WHERE seq < ?";
  if (tenant) sql += " AND tenant = ?";
  if (!states.empty()) {
    sql += " AND state IN (";
    for (std::size_t i = 0; i < states.size(); ++i) sql += i ? ",?" : "?";
    sql += ")";
  }
  sql += " ORDER BY seq DESC LIMIT ?";
  std::lock_guard lock(read_mutex_);
  Statement select(reader_, sql.c_str(), kStore);
  int index = 1;
  select.Bind(index++, before_seq > 0 ? before_seq : INT64_MAX);
  if (tenant) select.BindText(index++, *tenant);
  for (const auto state : states) select.Bind(index++, state);
  select.Bind(index, limit + 1);
  Page page;
  std::int64_t last_seq = 0;
  while (select.Step()) {
    if (static_cast<int>(page.jobs.size()) == limit) {
      page.next_before_seq = last_seq;
      break;
    }
    last_seq = select.Int(0);
    page.jobs.push_back(Parse(select.Blob(1), last_seq));
  }
  return page;
}

std::vector<StoredJob> JobStore::Unfinished() {
  Flush();
  std::lock_guard lock(mutex_);
  Statement select(db_, "SELECT seq, job FROM jobs WHERE state IN (?, ?) ORDER BY seq", kStore);
  select.Bind(1, v1::QUEUED);
  select.Bind(2, v1::RUNNING);
  std::vector<StoredJob> jobs;
  while (select.Step()) jobs.push_back({select.Int(0), Parse(select.Blob(1), select.Int(0))});
  return jobs;
}

std::map<v1::JobState, std::int64_t> JobStore::CountByState() {
  Flush();
  std::lock_guard lock(mutex_);
  Statement select(db_, "SELECT state, COUNT(*) FROM jobs GROUP BY state", kStore);
  std::map<v1::JobState, std::int64_t> counts;
  while (select.Step()) counts[static_cast<v1::JobState>(select.Int(0))] = select.Int(1);
  return counts;
}

JobStore::Usage JobStore::UsageOf(const std::string& tenant) {
  Flush();
  std::lock_guard lock(mutex_);
  Statement select(
      db_, "SELECT COALESCE(SUM(state IN (?, ?)), 0), COALESCE(SUM(bytes), 0) FROM jobs WHERE tenant = ?",
      kStore);
  select.Bind(1, v1::QUEUED);
  select.Bind(2, v1::RUNNING);
  select.BindText(3, tenant);
  select.Step();
  return {select.Int(0), select.Int(1)};
}

void JobStore::Scan(const std::function<void(const StoredJob&)>& visit) {
  Flush();
  std::lock_guard lock(mutex_);
  Statement select(db_, "SELECT seq, job FROM jobs ORDER BY seq", kStore);
  while (select.Step()) visit({select.Int(0), Parse(select.Blob(1), select.Int(0))});
}

bool JobStore::Broken() {
  std::lock_guard lock(staged_mutex_);
  return !broken_.empty();
}

bool JobStore::Writable() {
  try {
    Flush();
  } catch (const Error&) {
    return false;
  }
  std::lock_guard lock(mutex_);
  return sqlite3_exec(db_, "BEGIN IMMEDIATE; COMMIT;", nullptr, nullptr, nullptr) == SQLITE_OK;
}

}  // namespace endorecon::server
