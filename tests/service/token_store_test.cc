#include "server/token_store.h"

#include <gtest/gtest.h>
#include <sqlite3.h>
#include <sys/stat.h>

#include <chrono>
#include <thread>

#include "common/error.h"
#include "server/job_coordinator.h"
#include "tests/unit/clip_fixture.h"
#include "tests/unit/temp_dir.h"

namespace endorecon::server {
namespace {

ErrorCode CodeOf(const std::function<void()>& call) {
  try {
    call();
  } catch (const Error& e) {
    return e.code();
  }
  ADD_FAILURE() << "no error";
  return ErrorCode::kInternal;
}

TEST(TokenStoreTest, CreatedTokensVerifyAndOnlyTheirHashIsStored) {
  testing::TempDir dir("tokens");
  const auto path = TokenStore::PathIn(dir.path());
  std::string token;
  {
    TokenStore store(path);
    token = store.Create("alice", Role::kClient, "radiology");
  }
  struct stat info {};
  ASSERT_EQ(stat(path.c_str(), &info), 0);
  EXPECT_EQ(info.st_mode & 0777, 0600u);
  // A second process (the running server) sees the token.
  TokenStore reader(path);
  EXPECT_FALSE(reader.Empty());
  const auto record = reader.Verify(token);
  EXPECT_EQ(record.name, "alice");
  EXPECT_EQ(record.role, Role::kClient);
  EXPECT_EQ(record.tenant, "radiology");
  const auto secret = token.substr(token.rfind('.') + 1);
  EXPECT_EQ(secret.size(), 64u);
  for (const auto& file : std::filesystem::directory_iterator(dir.path()))
    EXPECT_EQ(testing::ReadBytes(file.path()).find(secret), std::string::npos) << file.path();
}

TEST(TokenStoreTest, RefusesMalformedUnknownForgedAndRevokedTokens) {
  testing::TempDir dir("tokens");
  TokenStore store(TokenStore::PathIn(dir.path()));
  const auto token = store.Create("node-1", Role::kWorker, "");
  EXPECT_EQ(CodeOf([&] { store.Verify("garbage"); }), ErrorCode::kUnauthenticated);
  EXPECT_EQ(CodeOf([&] { store.Verify(token + "0"); }), ErrorCode::kUnauthenticated);
  std::string forged = token;
  forged.back() = forged.back() == 'a' ? 'b' : 'a';
  EXPECT_EQ(CodeOf([&] { store.Verify(forged); }), ErrorCode::kUnauthenticated);
  std::string other_id = token;
  other_id[10] = other_id[10] == 'a' ? 'b' : 'a';
  EXPECT_EQ(CodeOf([&] { store.Verify(other_id); }), ErrorCode::kUnauthenticated);

  const auto revoked = store.Revoke("node-1");
  EXPECT_GT(revoked.revoked_unix_ms, 0);
  try {
    store.Verify(token);
    ADD_FAILURE() << "a revoked token verified";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kUnauthenticated);
    EXPECT_NE(std::string(e.what()).find("revoked"), std::string::npos);
    EXPECT_EQ(std::string(e.what()).find(token), std::string::npos);
  }
  // Revoked already: said so, not as an unknown name (found 2026-12-07).
  EXPECT_NE(testing::ErrorFrom([&] { store.Revoke("node-1"); }, ErrorCode::kNotFound)
                .find("every token of that name is revoked already"),
            std::string::npos);
  EXPECT_EQ(testing::ErrorFrom([&] { store.Revoke("nobody-such"); }, ErrorCode::kNotFound),
            "no active token named 'nobody-such'");
  // The label is free again; the old token stays revoked.
  const auto again = store.Create("node-1", Role::kWorker, "");
  EXPECT_EQ(store.Verify(again).name, "node-1");
  EXPECT_EQ(CodeOf([&] { store.Verify(token); }), ErrorCode::kUnauthenticated);
  const auto listed = store.List();
  ASSERT_EQ(listed.size(), 2u);
  EXPECT_GT(listed[0].revoked_unix_ms, 0);
  EXPECT_EQ(listed[1].revoked_unix_ms, 0);
}

TEST(TokenStoreTest, RefusesBadNamesTenantsAndDuplicates) {
  testing::TempDir dir("tokens");
  TokenStore store(TokenStore::PathIn(dir.path()));
  EXPECT_TRUE(store.Empty());  // a server requires tokens only once its store holds one
  store.Create("alice", Role::kClient, "radiology");
  EXPECT_EQ(CodeOf([&] { store.Create("alice", Role::kClient, "radiology"); }), ErrorCode::kInvalidArgument);
  EXPECT_EQ(CodeOf([&] { store.Create("bob", Role::kClient, ""); }), ErrorCode::kInvalidArgument);
  EXPECT_EQ(CodeOf([&] { store.Create("bob", Role::kClient, "Radiology"); }), ErrorCode::kInvalidArgument);
  EXPECT_EQ(CodeOf([&] { store.Create("bob", Role::kClient, "-x"); }), ErrorCode::kInvalidArgument);
  EXPECT_EQ(CodeOf([&] { store.Create("bob smith", Role::kClient, "x"); }), ErrorCode::kInvalidArgument);
  EXPECT_EQ(CodeOf([&] { store.Create("", Role::kAdmin, ""); }), ErrorCode::kInvalidArgument);
  EXPECT_EQ(store.List().size(), 1u);
}

TEST(TokenStoreTest, AnExpiredTokenIsRefusedAndGivesUpItsName) {
  testing::TempDir dir("tokens");
  TokenStore store(TokenStore::PathIn(dir.path()));
  EXPECT_EQ(CodeOf([&] { store.Create("past", Role::kClient, "x", NowUnixMs() - 1000); }),
            ErrorCode::kInvalidArgument);
  const auto expires = NowUnixMs() + 400;
  const auto token = store.Create("temp", Role::kClient, "radiology", expires);
  const auto lasting = store.Create("lasting", Role::kAdmin, "", NowUnixMs() + 3'600'000);
  EXPECT_EQ(store.Verify(token).expires_unix_ms, expires);
  EXPECT_EQ(store.Verify(token).StateAt(NowUnixMs()), "active");
  std::this_thread::sleep_until(
      std::chrono::system_clock::time_point(std::chrono::milliseconds(expires + 50)));
  try {
    store.Verify(token);
    ADD_FAILURE() << "an expired token verified";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kUnauthenticated);
    EXPECT_NE(std::string(e.what()).find("'temp' expired at"), std::string::npos) << e.what();
    EXPECT_EQ(std::string(e.what()).find(token), std::string::npos);
  }
  EXPECT_EQ(store.Verify(lasting).name, "lasting");
  // Revoking it sets it aside at its expiry, as a successor would: the alert on expired worker tokens
  // says to revoke it, and it was refused as expired (found 2026-12-07). Once only.
  EXPECT_EQ(store.Revoke("temp").revoked_unix_ms, expires);
  EXPECT_EQ(CodeOf([&] { store.Revoke("temp"); }), ErrorCode::kNotFound);
  // The expired token's name is free again; the token itself stays expired, not revoked.
  const auto renewed = store.Create("temp", Role::kClient, "radiology");
  EXPECT_EQ(store.Verify(renewed).expires_unix_ms, 0);
  EXPECT_EQ(CodeOf([&] { store.Verify(token); }), ErrorCode::kUnauthenticated);
  const auto listed = store.List();
  ASSERT_EQ(listed.size(), 3u);
  EXPECT_EQ(listed[0].StateAt(NowUnixMs()), "expired");
  EXPECT_EQ(listed[0].revoked_unix_ms, expires);
  EXPECT_EQ(listed[1].StateAt(NowUnixMs()), "active");
  EXPECT_EQ(listed[2].StateAt(NowUnixMs()), "active");
  // Revoked before it expired: revoked.
  store.Revoke("lasting");
  EXPECT_EQ(store.List()[1].StateAt(NowUnixMs() + 7'200'000), "revoked");
}

// A store written before tokens could expire gains the column, and its tokens never expire.
TEST(TokenStoreTest, AStoreFromBeforeExpiryKeepsItsTokens) {
  testing::TempDir dir("tokens");
  const auto path = TokenStore::PathIn(dir.path());
  std::string token;
  {
    TokenStore store(path);
    token = store.Create("old", Role::kWorker, "");
  }
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open(path.c_str(), &db), SQLITE_OK);
  ASSERT_EQ(sqlite3_exec(db, "ALTER TABLE tokens DROP COLUMN expires", nullptr, nullptr, nullptr), SQLITE_OK)
      << sqlite3_errmsg(db);
  sqlite3_close(db);
  TokenStore store(path);
  EXPECT_EQ(store.Verify(token).expires_unix_ms, 0);
  TokenStore second(path);  // opening it again adds nothing twice
  EXPECT_EQ(second.List().size(), 1u);
  EXPECT_NE(store.Create("new", Role::kAdmin, "", NowUnixMs() + 60'000), "");
}

}  // namespace
}  // namespace endorecon::server
