#include "server/sqlite_statement.h"

#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <string>

#include "common/error.h"
#include "server/wal_check.h"

namespace endorecon::server {

Statement::Statement(sqlite3* db, const char* sql, const char* store) : db_(db), store_(store) {
  if (sqlite3_prepare_v2(db, sql, -1, &stmt_, nullptr) != SQLITE_OK) Check(SQLITE_ERROR, sql);
}

Statement::~Statement() { sqlite3_finalize(stmt_); }

void Statement::Bind(int index, std::int64_t value) { sqlite3_bind_int64(stmt_, index, value); }

void Statement::Bind(int index, const std::string& value) {
  sqlite3_bind_blob(stmt_, index, value.data(), static_cast<int>(value.size()), SQLITE_TRANSIENT);
}

void Statement::BindText(int index, const std::string& value) {
  sqlite3_bind_text(stmt_, index, value.data(), static_cast<int>(value.size()), SQLITE_TRANSIENT);
}

void Statement::Reset() {
  sqlite3_reset(stmt_);
  sqlite3_clear_bindings(stmt_);
}

bool Statement::Step() {
  const int rc = sqlite3_step(stmt_);
  if (rc == SQLITE_ROW) return true;
  Check(rc == SQLITE_DONE ? SQLITE_OK : rc, "step");
  return false;
}

std::int64_t Statement::Int(int column) { return sqlite3_column_int64(stmt_, column); }

std::string Statement::Blob(int column) {
  const auto* data = static_cast<const char*>(sqlite3_column_blob(stmt_, column));
  return std::string(data ? data : "", static_cast<std::size_t>(sqlite3_column_bytes(stmt_, column)));
}

std::string Statement::Text(int column) {
  const auto* text = reinterpret_cast<const char*>(sqlite3_column_text(stmt_, column));
  return std::string(text ? text : "", static_cast<std::size_t>(sqlite3_column_bytes(stmt_, column)));
}

void Statement::Check(int rc, const char* what) {
  if (rc != SQLITE_OK) FailStore(db_, store_, std::string(what) + ": " + sqlite3_errmsg(db_));
}

void FailStore(sqlite3* db, const char* store, const std::string& what) {
  const int code = sqlite3_errcode(db) & 0xff;  // the primary result code
  const char* name = sqlite3_db_filename(db, "main");
  const std::filesystem::path file = name != nullptr ? name : "";
  const std::string where = file.empty() ? std::string(store) : file.string() + ": " + store;
  // A damaged file, a full disk and a read-only file are said as what they are: each was
  // "UNAVAILABLE: job store: step: ...", which reads as a moment's trouble (found 2026-12-05).
  if (code == SQLITE_CORRUPT || code == SQLITE_NOTADB) {
    Fail(ErrorCode::kDataLoss, where + ": " + what + "; the file is damaged: restore it from a backup " +
                                   "(docs/operations.md, \"Backup and restore\")");
  }
  if (code == SQLITE_FULL) Fail(ErrorCode::kResourceExhausted, where + ": " + what + " (its disk is full)");
  if (code == SQLITE_READONLY) Fail(ErrorCode::kFailedPrecondition, where + ": " + what);
  std::string note;
  if (code == SQLITE_IOERR && !file.empty()) {
    std::error_code error;
    const auto space = std::filesystem::space(file.parent_path(), error);
    if (!error && space.available < (std::uintmax_t{1} << 20)) {
      note = " (its disk has " + std::to_string(space.available) + " bytes free: it is full)";
    }
  }
  Fail(ErrorCode::kUnavailable, where + ": " + what + note);
}

void Exec(sqlite3* db, const char* sql, const char* store) {
  char* message = nullptr;
  if (sqlite3_exec(db, sql, nullptr, nullptr, &message) != SQLITE_OK) {
    const std::string text = message ? message : "unknown error";
    sqlite3_free(message);
    FailStore(db, store, text + " in: " + sql);
  }
}

sqlite3* OpenDatabase(const std::filesystem::path& file, const char* store) {
  // The file and its log and shared-memory files, before SQLite opens them: one this user may read
  // but not write (another user's, 0644) opened read-only without a word, and the first write
  // stopped the server ("attempt to write a readonly database"; found 2026-12-07).
  for (const char* suffix : {"", "-wal", "-shm"}) {
    const auto part = file.string() + suffix;
    if (::access(part.c_str(), F_OK) == 0 && ::access(part.c_str(), R_OK | W_OK) != 0) {
      Fail(ErrorCode::kFailedPrecondition,
           std::string("cannot open ") + store + " " + file.string() + ": " + part +
               " cannot be read and written by this user: " + std::strerror(errno) +
               " (a restored copy owned by another user? chown it to the server's user)");
    }
  }
  sqlite3* db = nullptr;
  if (sqlite3_open(file.c_str(), &db) != SQLITE_OK) {
    std::string message = db ? sqlite3_errmsg(db) : "out of memory";
    sqlite3_close(db);
    // SQLite says "unable to open database file" for a folder this user may not write (a read-only
    // mount, another user's folder): the folder is named.
    const auto folder = file.parent_path().empty() ? std::filesystem::path(".") : file.parent_path();
    const bool writable = ::access(folder.c_str(), W_OK) == 0;
    if (!writable) {
      message += " (its folder " + folder.string() +
                 " cannot be written by this user: " + std::strerror(errno) + ")";
    }
    Fail(writable ? ErrorCode::kUnavailable : ErrorCode::kFailedPrecondition,
         std::string("cannot open ") + store + " " + file.string() + ": " + message);
  }
  sqlite3_busy_timeout(db, 5000);
  try {
    Exec(db, "PRAGMA journal_mode=WAL", store);
    Exec(db, "PRAGMA synchronous=FULL", store);
  } catch (const Error&) {
    sqlite3_close(db);  // Exec's error names the file and says what it is
    throw;
  }
  return db;
}

sqlite3* OpenStore(const std::filesystem::path& file, const char* store) {
  // Before SQLite reads the log: it would drop what follows the damage and go on (wal_check.h).
  const std::filesystem::path wal = file.string() + "-wal";
  if (const auto damage = FindWalDamage(wal)) {
    Fail(ErrorCode::kDataLoss,
         std::string(store) + " " + file.string() + ": its write-ahead log " + wal.string() +
             " is damaged: " +
             (damage->bad_frame < 0 ? std::string("its header")
                                    : "frame " + std::to_string(damage->bad_frame)) +
             " fails its checksum, and " + std::to_string(damage->commits_after) +
             " committed transaction(s) follow, which SQLite would drop without a word (jobs accepted, "
             "tokens made). Restore the data folder from a backup (docs/operations.md, \"Backup and "
             "restore\"); or, to start with what the store held before the damage and lose what "
             "followed, move " +
             wal.filename().string() + " aside");
  }
  return OpenDatabase(file, store);
}

void CheckDatabase(sqlite3* db, const std::filesystem::path& file, const char* store) {
  if (sqlite3_db_readonly(db, "main") == 1) {
    Fail(ErrorCode::kFailedPrecondition, std::string(store) + " " + file.string() +
                                             " cannot be written by this user (its mode or owner: a restored "
                                             "copy owned by another user? chown it to the server's user)");
  }
  Statement check(db, "PRAGMA quick_check", store);
  std::string verdict;
  while (check.Step()) {
    if (!verdict.empty()) verdict += "; ";
    verdict += check.Text(0);
    if (verdict.size() > 300) break;
  }
  if (verdict != "ok") {
    Fail(ErrorCode::kDataLoss,
         std::string(store) + " " + file.string() + " is damaged (SQLite's quick_check: " + verdict +
             "); restore it from a backup (docs/operations.md, \"Backup and restore\")");
  }
}

}  // namespace endorecon::server
