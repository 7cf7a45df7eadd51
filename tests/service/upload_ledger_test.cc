#include "server/upload_ledger.h"

#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include "tests/unit/temp_dir.h"

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

// A server restart forgot the ledger: the uploads from before it stopped counting and `endorecon
// uploads` listed none of them (found 2026-12-06). It is kept in a file, read at start.
TEST(UploadLedgerTest, TheLedgerOutlivesARestartInItsFile) {
  testing::TempDir dir("ledger");
  const auto file = dir / "uploads.json";
  const auto t0 = UploadLedger::Time::clock::now();
  const auto none = [](const std::string&) { return false; };
  // Digests as the file keeps them (64 hex digits): an entry with another is no upload.
  const std::string x(64, '1'), y(64, '2'), z(64, '3'), w(64, '4');
  {
    UploadLedger ledger;
    ledger.KeepIn(file);
    EXPECT_FALSE(std::filesystem::exists(file)) << "written at the first change";
    ledger.Note("a", Files({{x.c_str(), 100}, {y.c_str(), 20}}), none, t0);
    ledger.Note("b", Files({{z.c_str(), 7}}), none, t0);
    ledger.Submitted("a", Files({{y.c_str(), 20}}));
    ledger.NoteProven("a", x);                              // a's upload sent every byte of x
    ledger.NoteProven("b", x);                              // b never noted x: nothing to prove
    ledger.Note("a", Files({{x.c_str(), 100}}), none, t0);  // noted again: still proven
  }
  UploadLedger restarted;
  restarted.KeepIn(file);
  EXPECT_EQ(restarted.PendingBytes("a", {}), 100);
  EXPECT_EQ(restarted.PendingBytes("b", {}), 7);
  EXPECT_EQ(restarted.Proven(), (std::vector<std::pair<std::string, std::string>>{{"a", x}}));
  EXPECT_EQ(restarted.ForgetBefore(t0 - std::chrono::minutes(1)), 0u) << "dated as when noted, not older";
  EXPECT_EQ(restarted.ForgetBefore(UploadLedger::Time::clock::now() + std::chrono::minutes(1)), 2u)
      << "nor newer";
  UploadLedger emptied;
  emptied.KeepIn(file);
  EXPECT_TRUE(emptied.Tenants().empty()) << "the forgetting was written";

  // A file that is no ledger is left aside (the server starts), and replaced at the next change.
  std::ofstream(file) << "{\"uploads\": [{\"tenant\": 5}]}";
  UploadLedger broken;
  broken.KeepIn(file);
  EXPECT_TRUE(broken.Tenants().empty());
  broken.Note("c", Files({{w.c_str(), 1}}), none, t0);
  UploadLedger again;
  again.KeepIn(file);
  EXPECT_EQ(again.PendingBytes("c", {}), 1);

  // An entry that is no upload (a bad tenant, digest or size) is left out; the others are read.
  std::ofstream(file) << R"({"uploads": [{"tenant": "Bad Name", "sha256": ")" << x
                      << R"(", "bytes": 5, "noted_unix_ms": 1}, {"tenant": "d", "sha256": "zz", "bytes": 5,
                      "noted_unix_ms": 1}, {"tenant": "d", "sha256": ")"
                      << x << R"(", "bytes": -5, "noted_unix_ms": 1}, {"tenant": "", "sha256": ")" << y
                      << R"(", "bytes": 9, "noted_unix_ms": 1765000000000}]})";
  UploadLedger mixed;
  mixed.KeepIn(file);
  const auto tenants = mixed.Tenants();
  ASSERT_EQ(tenants.size(), 1u);
  EXPECT_EQ(tenants.begin()->first, "") << "the admins' tenant";
  EXPECT_EQ(tenants.begin()->second.bytes, 9);
}

// Written at each proven file, the ledger's whole file made an upload of N files write O(N^2) bytes:
// 10,001 files missed the client's deadline (found 2026-12-06). A proven mark is written once a
// second has passed since the last write, and at the upload's end (Flush).
TEST(UploadLedgerTest, ProvenMarksAreWrittenOnceASecondAndAtTheUploadsEnd) {
  testing::TempDir dir("ledger");
  const auto file = dir / "uploads.json";
  const auto none = [](const std::string&) { return false; };
  const auto proven_in_file = [&] {
    UploadLedger read;
    read.KeepIn(file);
    return read.Proven().size();
  };
  const std::string x(64, '1'), y(64, '2'), z(64, '3');
  UploadLedger ledger;
  ledger.KeepIn(file);
  const auto written = std::chrono::steady_clock::now();
  ledger.Note("a", Files({{x.c_str(), 1}, {y.c_str(), 2}, {z.c_str(), 3}}), none,
              UploadLedger::Time::clock::now());
  ledger.NoteProven("a", x);
  ledger.NoteProven("a", y);
  if (std::chrono::steady_clock::now() - written < std::chrono::milliseconds(900)) {
    EXPECT_EQ(proven_in_file(), 0u) << "within a second of the last write";
  }
  ledger.Flush();
  EXPECT_EQ(proven_in_file(), 2u);
  std::this_thread::sleep_for(std::chrono::milliseconds(1100));
  ledger.NoteProven("a", z);
  EXPECT_EQ(proven_in_file(), 3u) << "a second after the last write";
}

}  // namespace
}  // namespace endorecon::server
