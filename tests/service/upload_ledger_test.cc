#include "server/upload_ledger.h"

#include <gtest/gtest.h>

#include <chrono>
#include <string>
#include <vector>

namespace endorecon::server {
namespace {

v1::Manifest Files(std::initializer_list<std::pair<const char*, std::int64_t>> files) {
  v1::Manifest manifest;
  for (const auto& [digest, size] : files) {
    auto* file = manifest.add_files();
    file->set_path(std::string(digest) + ".png");
    file->set_sha256(digest);
    file->set_size(size);
  }
  return manifest;
}

TEST(UploadLedgerTest, ATenantsUploadsCountUntilSubmittedOrForgotten) {
  UploadLedger ledger;
  const auto t0 = UploadLedger::Time::clock::now();
  const auto stored = [](const std::string& digest) { return digest == "stored"; };
  ledger.Note("a", Files({{"x", 100}, {"y", 20}, {"stored", 5000}}), stored, t0);
  EXPECT_EQ(ledger.PendingBytes("a", {}), 120) << "a file already stored brings nothing";
  EXPECT_EQ(ledger.PendingBytes("b", {}), 0);
  EXPECT_EQ(ledger.PendingBytes("a", Files({{"x", 100}})), 20) << "the manifest asked about is left out";
  ledger.Note("a", Files({{"z", 3}}), stored, t0 + std::chrono::hours(2));
  ledger.Submitted("a", Files({{"y", 20}}));
  EXPECT_EQ(ledger.PendingBytes("a", {}), 103);
  EXPECT_EQ(ledger.ForgetBefore(t0 + std::chrono::hours(1)), 1u) << "x, noted before the cutoff";
  EXPECT_EQ(ledger.PendingBytes("a", {}), 3);
  ledger.Note("a", Files({{"z", 3}}), stored, t0 + std::chrono::hours(5));
  EXPECT_EQ(ledger.ForgetBefore(t0 + std::chrono::hours(3)), 0u) << "noted again: dated anew";
  ledger.Submitted("a", Files({{"z", 3}}));
  EXPECT_EQ(ledger.PendingBytes("a", {}), 0);
}

TEST(UploadLedgerTest, ATenantsUploadsAreListedAndDroppedAlone) {
  UploadLedger ledger;
  const auto t0 = UploadLedger::Time::clock::now();
  const auto none = [](const std::string&) { return false; };
  ledger.Note("a", Files({{"x", 100}, {"shared", 20}}), none, t0);
  ledger.Note("b", Files({{"shared", 20}}), none, t0);
  const auto tenants = ledger.Tenants();
  ASSERT_EQ(tenants.size(), 2u);
  EXPECT_EQ(tenants.at("a").files, 2);
  EXPECT_EQ(tenants.at("a").bytes, 120);
  EXPECT_GT(tenants.at("a").last_unix_ms, 0);
  EXPECT_EQ(tenants.at("b").bytes, 20);
  EXPECT_EQ(ledger.Drop("a"), (std::vector<std::string>{"shared", "x"}));
  EXPECT_TRUE(ledger.Drop("a").empty()) << "dropped once";
  EXPECT_EQ(ledger.PendingBytes("a", {}), 0);
  EXPECT_TRUE(ledger.Holds("shared")) << "b's upload still brings it";
  EXPECT_FALSE(ledger.Holds("x"));
  EXPECT_EQ(ledger.Tenants().count("a"), 0u);
}

}  // namespace
}  // namespace endorecon::server
