#include "server/token_store.h"

#include <fmt/chrono.h>
#include <fmt/format.h>
#include <openssl/crypto.h>

#include "common/error.h"
#include "common/sha256.h"
#include "server/job_coordinator.h"
#include "server/lease_table.h"
#include "server/sqlite_statement.h"
#include "server/unix_time.h"

namespace endorecon::server {
namespace {

constexpr const char* kStore = "token store";
constexpr std::string_view kPrefix = "endorecon.";
constexpr int kIdBytes = 8;
constexpr int kSecretBytes = 32;

bool IsHex(std::string_view text, std::size_t length) {
  return text.size() == length && text.find_first_not_of("0123456789abcdef") == std::string_view::npos;
}

std::string HashOf(const std::string& salt, std::string_view secret) {
  Sha256 digest;
  digest.Update(salt);
  digest.Update(secret);
  return digest.HexDigest();
}

void ValidateName(const std::string& name) {
  if (name.empty() || name.size() > 64 ||
      name.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789._@-") !=
          std::string::npos) {
    FailInvalid("token name '" + name + "': expected 1-64 characters of letters, digits, '.', '_', '@', '-'");
  }
}

// Stores made before tokens could expire lack the column; it is added once, in a write transaction
// so that the server and `token ...` opening the same old store at once add it only once.
void AddExpiryColumn(sqlite3* db) {
  Exec(db, "BEGIN IMMEDIATE", kStore);
  try {
    Statement has(db, "SELECT COUNT(*) FROM pragma_table_info('tokens') WHERE name = 'expires'", kStore);
    has.Step();
    if (has.Int(0) == 0) Exec(db, "ALTER TABLE tokens ADD COLUMN expires INTEGER NOT NULL DEFAULT 0", kStore);
    Exec(db, "COMMIT", kStore);
  } catch (...) {
    sqlite3_exec(db, "ROLLBACK", nullptr, nullptr, nullptr);
    throw;
  }
}

}  // namespace

std::string_view TokenRecord::StateAt(std::int64_t now_unix_ms) const {
  const bool expired = expires_unix_ms != 0 && expires_unix_ms <= now_unix_ms;
  if (revoked_unix_ms != 0 && !(expired && revoked_unix_ms >= expires_unix_ms)) return "revoked";
  return expired ? "expired" : "active";
}

std::filesystem::path TokenStore::PathIn(const std::filesystem::path& data_dir) {
  return data_dir / "tokens.sqlite";
}

TokenStore::TokenStore(const std::filesystem::path& db_file) {
  const bool created = !std::filesystem::exists(db_file);
  db_ = OpenStore(db_file, kStore);
  if (created) {
    std::error_code ignored;
    std::filesystem::permissions(
        db_file, std::filesystem::perms::owner_read | std::filesystem::perms::owner_write, ignored);
  }
  try {
    CheckDatabase(db_, db_file, kStore);
    Exec(db_,
         "CREATE TABLE IF NOT EXISTS tokens ("
         " id TEXT PRIMARY KEY,"
         " name TEXT NOT NULL,"
         " role TEXT NOT NULL,"
         " tenant TEXT NOT NULL,"
         " salt TEXT NOT NULL,"
         " hash TEXT NOT NULL,"
         " created INTEGER NOT NULL,"
         " revoked INTEGER NOT NULL DEFAULT 0)",
         kStore);
    Exec(db_, "CREATE UNIQUE INDEX IF NOT EXISTS tokens_active_name ON tokens(name) WHERE revoked = 0",
         kStore);
    AddExpiryColumn(db_);
  } catch (...) {
    sqlite3_close(db_);
    throw;
  }
}

TokenStore::~TokenStore() { sqlite3_close(db_); }

void ValidateTokenRequest(const std::string& name, Role role, const std::string& tenant,
                          std::int64_t expires_unix_ms, std::int64_t now_unix_ms) {
  ValidateName(name);
  if (expires_unix_ms != 0 && expires_unix_ms <= now_unix_ms)
    FailInvalid("token '" + name + "': its expiry " + UtcText(expires_unix_ms) + " is not in the future");
  if (!tenant.empty() || role == Role::kClient) {
    if (tenant.empty()) FailInvalid("a client token needs --tenant: its jobs belong to that tenant");
    ValidateTenant(tenant);
  }
}

std::string TokenStore::Create(const std::string& name, Role role, const std::string& tenant,
                               std::int64_t expires_unix_ms) {
  const std::int64_t now = NowUnixMs();
  ValidateTokenRequest(name, role, tenant, expires_unix_ms, now);
  const std::string id = RandomId(kIdBytes);
  const std::string secret = RandomId(kSecretBytes);
  const std::string salt = RandomId(16);
  std::lock_guard lock(mutex_);
  {
    // An expired token gives up its name: it is marked revoked at the moment it expired.
    Statement retire(db_,
                     "UPDATE tokens SET revoked = expires WHERE name = ? AND revoked = 0 AND expires != 0 "
                     "AND expires <= ?",
                     kStore);
    retire.BindText(1, name);
    retire.Bind(2, now);
    retire.Step();
    Statement active(db_, "SELECT COUNT(*) FROM tokens WHERE name = ? AND revoked = 0", kStore);
    active.BindText(1, name);
    active.Step();
    if (active.Int(0) > 0)
      FailInvalid("an active token is named '" + name + "'; revoke it first or pick another name");
  }
  Statement insert(db_,
                   "INSERT INTO tokens(id, name, role, tenant, salt, hash, created, expires) "
                   "VALUES(?, ?, ?, ?, ?, ?, ?, ?)",
                   kStore);
  insert.BindText(1, id);
  insert.BindText(2, name);
  insert.BindText(3, RoleName(role));
  insert.BindText(4, tenant);
  insert.BindText(5, salt);
  insert.BindText(6, HashOf(salt, secret));
  insert.Bind(7, now);
  insert.Bind(8, expires_unix_ms);
  insert.Step();
  return std::string(kPrefix) + id + "." + secret;
}

std::vector<TokenRecord> TokenStore::List() {
  std::lock_guard lock(mutex_);
  Statement select(db_,
                   "SELECT name, role, tenant, created, revoked, expires FROM tokens ORDER BY created, rowid",
                   kStore);
  std::vector<TokenRecord> records;
  while (select.Step()) {
    records.push_back({select.Text(0), ParseRole(select.Text(1)).value_or(Role::kClient), select.Text(2),
                       select.Int(3), select.Int(4), select.Int(5)});
  }
  return records;
}

bool TokenStore::Empty() {
  std::lock_guard lock(mutex_);
  Statement any(db_, "SELECT EXISTS(SELECT 1 FROM tokens)", kStore);
  any.Step();
  return any.Int(0) == 0;
}

TokenRecord TokenStore::Revoke(const std::string& name) {
  std::lock_guard lock(mutex_);
  TokenRecord record;
  {
    Statement select(db_, "SELECT role, tenant, created, expires FROM tokens WHERE name = ? AND revoked = 0",
                     kStore);
    select.BindText(1, name);
    if (!select.Step()) {
      // A label whose tokens are all revoked or set aside (an expired one is, when a successor takes
      // its label) read as unknown while `token list` showed it (found 2026-12-07).
      Statement known(db_, "SELECT COUNT(*) FROM tokens WHERE name = ?", kStore);
      known.BindText(1, name);
      const bool listed = known.Step() && known.Int(0) > 0;
      Fail(ErrorCode::kNotFound,
           "no active token named '" + name + "'" +
               (listed ? ": every token of that name is revoked already or, expired, set aside (`token list` "
                         "shows them; nothing to do)"
                       : ""));
    }
    // An expired token is set aside as its successor would set it (revoked at its expiry, listed as
    // expired): that ends EndoreconWorkerTokenExpired, whose text says to revoke it (it was refused as
    // expired already, and the alert went on; found 2026-12-07).
    const std::int64_t expires = select.Int(3), now = NowUnixMs();
    record = {name,          ParseRole(select.Text(0)).value_or(Role::kClient), select.Text(1),
              select.Int(2), expires != 0 && expires <= now ? expires : now,    expires};
  }
  Statement update(db_, "UPDATE tokens SET revoked = ? WHERE name = ? AND revoked = 0", kStore);
  update.Bind(1, record.revoked_unix_ms);
  update.BindText(2, name);
  update.Step();
  return record;
}

TokenRecord TokenStore::Verify(std::string_view token, TokenRecord* refused) {
  const auto dot = token.find('.', kPrefix.size());
  if (token.substr(0, kPrefix.size()) != kPrefix || dot == std::string_view::npos ||
      !IsHex(token.substr(kPrefix.size(), dot - kPrefix.size()), 2 * kIdBytes) ||
      !IsHex(token.substr(dot + 1), 2 * kSecretBytes)) {
    Fail(ErrorCode::kUnauthenticated,
         "malformed token: expected endorecon.<id>.<secret> as printed by "
         "`endorecon-server token create`");
  }
  const std::string id(token.substr(kPrefix.size(), dot - kPrefix.size()));
  std::lock_guard lock(mutex_);
  Statement select(
      db_, "SELECT name, role, tenant, salt, hash, created, revoked, expires FROM tokens WHERE id = ?",
      kStore);
  select.BindText(1, id);
  if (!select.Step()) Fail(ErrorCode::kUnauthenticated, "unknown token");
  const std::string expected = select.Text(4);
  const std::string actual = HashOf(select.Text(3), token.substr(dot + 1));
  if (actual.size() != expected.size() || CRYPTO_memcmp(actual.data(), expected.data(), actual.size()) != 0)
    Fail(ErrorCode::kUnauthenticated, "unknown token");
  const TokenRecord record{select.Text(0), ParseRole(select.Text(1)).value_or(Role::kClient),
                           select.Text(2), select.Int(5),
                           select.Int(6),  select.Int(7)};
  const auto state = record.StateAt(NowUnixMs());
  if (refused != nullptr && state != "active") *refused = record;
  if (state == "revoked") Fail(ErrorCode::kUnauthenticated, "the token '" + record.name + "' was revoked");
  if (state == "expired") {
    Fail(ErrorCode::kUnauthenticated, "the token '" + record.name + "' expired at " +
                                          UtcText(record.expires_unix_ms) + "; ask its issuer for a new one");
  }
  return record;
}

}  // namespace endorecon::server
