// The SQLite pieces the server's stores share (jobs.sqlite, tokens.sqlite): a prepared statement
// that finalizes itself and turns every failure into Error(kUnavailable) naming the store.
#pragma once

#include <sqlite3.h>

#include <cstdint>
#include <filesystem>
#include <string>

namespace endorecon::server {

class Statement {
 public:
  // Throws Error(kUnavailable) "<store>: ..." when `sql` does not prepare.
  Statement(sqlite3* db, const char* sql, const char* store);
  ~Statement();
  Statement(const Statement&) = delete;
  Statement& operator=(const Statement&) = delete;

  void Bind(int index, std::int64_t value);
  void Bind(int index, const std::string& value);  // as a blob
  void BindText(int index, const std::string& value);
  // Makes the statement ready to run again with new bindings.
  void Reset();
  // True while there is a row; false when done. Throws Error(kUnavailable) on an error.
  bool Step();
  std::int64_t Int(int column);
  std::string Blob(int column);
  std::string Text(int column);

 private:
  void Check(int rc, const char* what);
  sqlite3* db_;
  const char* store_;
  sqlite3_stmt* stmt_ = nullptr;
};

// Throws the error of `db`'s last failed call, naming its file, `store` and `what`: kDataLoss for a
// damaged file (with how to restore it), kResourceExhausted for a full disk, kFailedPrecondition for a
// read-only one, else kUnavailable (an I/O error with the disk's free bytes when they are few).
[[noreturn]] void FailStore(sqlite3* db, const char* store, const std::string& what);

// Runs statements without results. Throws as FailStore, naming the SQL.
void Exec(sqlite3* db, const char* sql, const char* store);

// Opens (creating) a database in WAL mode with synchronous=FULL and a busy timeout, so several
// processes (the server, `endorecon-server token ...`) may use it at once. Throws
// Error(kUnavailable) naming the file.
sqlite3* OpenDatabase(const std::filesystem::path& file, const char* store);

// A store's first connection: OpenDatabase, once its write-ahead log is read for committed
// transactions past a damaged frame (wal_check.h), which SQLite would drop in silence:
// Error(kDataLoss) naming the frame. Its further connections (a reader, the checkpointer) open the
// log this one has already taken, with OpenDatabase.
sqlite3* OpenStore(const std::filesystem::path& file, const char* store);

// What a store's owner checks once at start, on its writing connection: that this process may write
// the file (Error(kFailedPrecondition) naming it: a read-only jobs.sqlite started, accepted uploads,
// then stopped at the first submit) and that SQLite's quick_check finds it whole (Error(kDataLoss):
// a damaged file served its listing and failed each job's status as "unavailable").
void CheckDatabase(sqlite3* db, const std::filesystem::path& file, const char* store);

}  // namespace endorecon::server
