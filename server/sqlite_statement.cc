#include "server/sqlite_statement.h"

#include <string>

#include "common/error.h"

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
  if (rc != SQLITE_OK)
    Fail(ErrorCode::kUnavailable, std::string(store_) + ": " + what + ": " + sqlite3_errmsg(db_));
}

void Exec(sqlite3* db, const char* sql, const char* store) {
  char* message = nullptr;
  if (sqlite3_exec(db, sql, nullptr, nullptr, &message) != SQLITE_OK) {
    const std::string text = message ? message : "unknown error";
    sqlite3_free(message);
    Fail(ErrorCode::kUnavailable, std::string(store) + ": " + text + " in: " + sql);
  }
}

sqlite3* OpenDatabase(const std::filesystem::path& file, const char* store) {
  sqlite3* db = nullptr;
  if (sqlite3_open(file.c_str(), &db) != SQLITE_OK) {
    const std::string message = db ? sqlite3_errmsg(db) : "out of memory";
    sqlite3_close(db);
    Fail(ErrorCode::kUnavailable, std::string("cannot open ") + store + " " + file.string() + ": " + message);
  }
  sqlite3_busy_timeout(db, 5000);
  try {
    Exec(db, "PRAGMA journal_mode=WAL", store);
    Exec(db, "PRAGMA synchronous=FULL", store);
  } catch (const Error& e) {
    // A file that is no database, or a damaged one, is named (the message named only the store).
    const int code = sqlite3_errcode(db);
    sqlite3_close(db);
    const bool damaged = code == SQLITE_CORRUPT || code == SQLITE_NOTADB;
    Fail(
        damaged ? ErrorCode::kDataLoss : e.code(),
        file.string() + ": " + e.what() + (damaged ? "; restore it from a backup (docs/operations.md)" : ""));
  }
  return db;
}

void CheckDatabase(sqlite3* db, const std::filesystem::path& file, const char* store) {
  if (sqlite3_db_readonly(db, "main") == 1) {
    Fail(ErrorCode::kFailedPrecondition, std::string(store) + " " + file.string() +
                                             " cannot be written by this user (its mode or owner: a restored "
                                             "copy owned by another user?)");
  }
  Statement check(db, "PRAGMA quick_check", store);
  std::string verdict;
  while (check.Step()) {
    if (!verdict.empty()) verdict += "; ";
    verdict += check.Text(0);
    if (verdict.size() > 300) break;
  }
  if (verdict != "ok") {
    Fail(ErrorCode::kDataLoss, std::string(store) + " " + file.string() +
                                   " is damaged (SQLite's quick_check: " + verdict +
                                   "); restore it from a backup (docs/operations.md)");
  }
}

}  // namespace endorecon::server
