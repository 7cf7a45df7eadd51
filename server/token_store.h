// Bearer tokens: <data-dir>/tokens.sqlite (SQLite, WAL), written by `endorecon-server token ...`
// and read by the running server on every call, so a created or revoked token counts at once.
//
// A token is "endorecon.<id>.<secret>": 8 random bytes of id (the row's key) and 32 of secret, in
// hex. Only the id, a random salt and SHA-256(salt || secret) are stored; the token itself exists
// once, in the output of Create. A fast hash is enough because the secret is 256 random bits, not a
// password: there is nothing to guess that a slow hash would protect.
#pragma once

#include <sqlite3.h>

#include <cstdint>
#include <filesystem>
#include <mutex>
#include <string>
#include <string_view>
#include <vector>

#include "server/principal.h"

namespace endorecon::server {

struct TokenRecord {
  std::string name;  // the label: unique among active tokens
  Role role = Role::kClient;
  std::string tenant;
  std::int64_t created_unix_ms = 0;
  std::int64_t revoked_unix_ms = 0;  // 0 unless revoked
  std::int64_t expires_unix_ms = 0;  // 0: never expires

  // "active", "revoked" or "expired" at `now_unix_ms`: a token revoked before its expiry is revoked.
  std::string_view StateAt(std::int64_t now_unix_ms) const;
};

class TokenStore {
 public:
  // <data_dir>/tokens.sqlite.
  static std::filesystem::path PathIn(const std::filesystem::path& data_dir);

  // Opens or creates the store (created with mode 0600). Throws Error(kUnavailable) naming the file.
  explicit TokenStore(const std::filesystem::path& db_file);
  ~TokenStore();
  TokenStore(const TokenStore&) = delete;
  TokenStore& operator=(const TokenStore&) = delete;

  // Creates a token and returns it (the only copy); it is refused from `expires_unix_ms` on (0: never).
  // Throws Error(kInvalidArgument) for a bad name or tenant (saying which characters are allowed), a
  // client token without a tenant, an expiry not in the future, or a name an active token already has.
  // The name of an expired token is free: that token is marked revoked at its expiry.
  std::string Create(const std::string& name, Role role, const std::string& tenant,
                     std::int64_t expires_unix_ms = 0);
  // Every token ever created (active and revoked), oldest first. Never a secret or a hash.
  std::vector<TokenRecord> List();
  // Whether no token was ever created in the store (a store left empty requires nothing).
  bool Empty();
  // Revokes the active token named `name`; returns its record. An expired one is revoked at its
  // expiry (it stays listed as expired). Throws Error(kNotFound).
  TokenRecord Revoke(const std::string& name);
  // The active token's record. Throws Error(kUnauthenticated) saying whether the token is malformed,
  // unknown, revoked or expired (never echoing it).
  // `refused` (optional) receives the record of a token whose secret matched but that is revoked or
  // expired, so the refusal can be traced to it (the audit log's principal).
  TokenRecord Verify(std::string_view token, TokenRecord* refused = nullptr);

 private:
  sqlite3* db_ = nullptr;
  std::mutex mutex_;
};

// What Create refuses before it touches the store: a bad name or tenant, a client token without a
// tenant, an expiry not after `now_unix_ms`. Throws Error(kInvalidArgument) saying which.
void ValidateTokenRequest(const std::string& name, Role role, const std::string& tenant,
                          std::int64_t expires_unix_ms, std::int64_t now_unix_ms);

}  // namespace endorecon::server
