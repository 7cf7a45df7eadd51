#include "server/job_store.h"

#include "common/error.h"

namespace endorecon::server {
namespace {

// A prepared statement that finalizes itself.
class Statement {
 public:
  Statement(sqlite3* db, const char* sql) : db_(db) {
    if (sqlite3_prepare_v2(db, sql, -1, &stmt_, nullptr) != SQLITE_OK) Check(SQLITE_ERROR, sql);
  }
  ~Statement() { sqlite3_finalize(stmt_); }
  Statement(const Statement&) = delete;
  Statement& operator=(const Statement&) = delete;

  void Bind(int index, std::int64_t value) { sqlite3_bind_int64(stmt_, index, value); }
  void Bind(int index, const std::string& value) {
    sqlite3_bind_blob(stmt_, index, value.data(), static_cast<int>(value.size()), SQLITE_TRANSIENT);
  }
  void BindText(int index, const std::string& value) {
    sqlite3_bind_text(stmt_, index, value.data(), static_cast<int>(value.size()), SQLITE_TRANSIENT);
  }
  // True while there is a row; false when done.
  bool Step() {
    const int rc = sqlite3_step(stmt_);
    if (rc == SQLITE_ROW) return true;
    Check(rc == SQLITE_DONE ? SQLITE_OK : rc, "step");
    return false;
  }
  std::int64_t Int(int column) { return sqlite3_column_int64(stmt_, column); }
  std::string Blob(int column) {
    const auto* data = static_cast<const char*>(sqlite3_column_blob(stmt_, column));
    return std::string(data ? data : "", static_cast<std::size_t>(sqlite3_column_bytes(stmt_, column)));
  }

 private:
  void Check(int rc, const char* what) {
    if (rc != SQLITE_OK)
      Fail(ErrorCode::kUnavailable, std::string("job store: ") + what + ": " + sqlite3_errmsg(db_));
  }
  sqlite3* db_;
  sqlite3_stmt* stmt_ = nullptr;
};

void Exec(sqlite3* db, const char* sql) {
  char* message = nullptr;
  if (sqlite3_exec(db, sql, nullptr, nullptr, &message) != SQLITE_OK) {
    const std::string text = message ? message : "unknown error";
    sqlite3_free(message);
    Fail(ErrorCode::kUnavailable, std::string("job store: ") + text + " in: " + sql);
  }
}

v1::Job Parse(const std::string& bytes, std::int64_t seq) {
  v1::Job job;
  if (!job.ParseFromString(bytes))
    Fail(ErrorCode::kDataLoss, "job store: row " + std::to_string(seq) + " is corrupt");
  return job;
}

}  // namespace

JobStore::JobStore(const std::filesystem::path& db_file) {
  if (sqlite3_open(db_file.c_str(), &db_) != SQLITE_OK) {
    const std::string message = db_ ? sqlite3_errmsg(db_) : "out of memory";
    sqlite3_close(db_);
    Fail(ErrorCode::kUnavailable, "cannot open job store " + db_file.string() + ": " + message);
  }
  sqlite3_busy_timeout(db_, 5000);
  Exec(db_, "PRAGMA journal_mode=WAL");
  Exec(db_, "PRAGMA synchronous=FULL");
  Exec(db_,
       "CREATE TABLE IF NOT EXISTS jobs ("
       " seq INTEGER PRIMARY KEY AUTOINCREMENT,"
       " id TEXT NOT NULL UNIQUE,"
       " state INTEGER NOT NULL,"
       " priority INTEGER NOT NULL,"
       " job BLOB NOT NULL)");
  Exec(db_, "CREATE INDEX IF NOT EXISTS jobs_state ON jobs(state, seq)");
}

JobStore::~JobStore() { sqlite3_close(db_); }

std::int64_t JobStore::Insert(const v1::Job& job) {
  std::lock_guard lock(mutex_);
  Statement insert(db_, "INSERT INTO jobs(id, state, priority, job) VALUES(?, ?, ?, ?)");
  insert.BindText(1, job.id());
  insert.Bind(2, job.state());
  insert.Bind(3, job.priority());
  insert.Bind(4, job.SerializeAsString());
  insert.Step();
  return sqlite3_last_insert_rowid(db_);
}

void JobStore::Update(const v1::Job& job) {
  std::lock_guard lock(mutex_);
  Statement update(db_, "UPDATE jobs SET state = ?, priority = ?, job = ? WHERE id = ?");
  update.Bind(1, job.state());
  update.Bind(2, job.priority());
  update.Bind(3, job.SerializeAsString());
  update.BindText(4, job.id());
  update.Step();
  if (sqlite3_changes(db_) == 0) Fail(ErrorCode::kNotFound, "no job " + job.id());
}

std::optional<StoredJob> JobStore::Get(const std::string& id) {
  std::lock_guard lock(mutex_);
  Statement select(db_, "SELECT seq, job FROM jobs WHERE id = ?");
  select.BindText(1, id);
  if (!select.Step()) return std::nullopt;
  return StoredJob{select.Int(0), Parse(select.Blob(1), select.Int(0))};
}

JobStore::Page JobStore::List(const std::vector<v1::JobState>& states, int limit, std::int64_t before_seq) {
  std::string sql = "SELECT seq, job FROM jobs WHERE seq < ?";
  if (!states.empty()) {
    sql += " AND state IN (";
    for (std::size_t i = 0; i < states.size(); ++i) sql += i ? ",?" : "?";
    sql += ")";
  }
  sql += " ORDER BY seq DESC LIMIT ?";
  std::lock_guard lock(mutex_);
  Statement select(db_, sql.c_str());
  int index = 1;
  select.Bind(index++, before_seq > 0 ? before_seq : INT64_MAX);
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
  std::lock_guard lock(mutex_);
  Statement select(db_, "SELECT seq, job FROM jobs WHERE state IN (?, ?) ORDER BY seq");
  select.Bind(1, v1::QUEUED);
  select.Bind(2, v1::RUNNING);
  std::vector<StoredJob> jobs;
  while (select.Step()) jobs.push_back({select.Int(0), Parse(select.Blob(1), select.Int(0))});
  return jobs;
}

std::map<v1::JobState, std::int64_t> JobStore::CountByState() {
  std::lock_guard lock(mutex_);
  Statement select(db_, "SELECT state, COUNT(*) FROM jobs GROUP BY state");
  std::map<v1::JobState, std::int64_t> counts;
  while (select.Step()) counts[static_cast<v1::JobState>(select.Int(0))] = select.Int(1);
  return counts;
}

bool JobStore::Writable() {
  std::lock_guard lock(mutex_);
  return sqlite3_exec(db_, "BEGIN IMMEDIATE; COMMIT;", nullptr, nullptr, nullptr) == SQLITE_OK;
}

}  // namespace endorecon::server
