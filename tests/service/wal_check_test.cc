#include "server/wal_check.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "common/error.h"
#include "server/job_store.h"
#include "tests/unit/temp_dir.h"

namespace endorecon::server {
namespace {

namespace fs = std::filesystem;

// A copy of a live store's files (the WAL not checkpointed: the store is still open), as a backup
// taken with cp or a disk's state at a crash.
void CopyLiveStore(const fs::path& from, const fs::path& to, int jobs) {
  fs::create_directories(from);
  JobStore store(from / "jobs.sqlite");
  for (int i = 0; i < jobs; ++i) {
    v1::Job job;
    job.set_id("job-" + std::to_string(i));
    job.set_name(std::string(3000, 'a' + i % 26));  // a page or so each: several frames a commit
    store.Insert(job);
    store.Flush();
  }
  fs::create_directories(to);
  fs::copy_file(from / "jobs.sqlite", to / "jobs.sqlite");
  fs::copy_file(from / "jobs.sqlite-wal", to / "jobs.sqlite-wal");
}

void FlipByte(const fs::path& file, std::int64_t at) {
  std::fstream io(file, std::ios::in | std::ios::out | std::ios::binary);
  io.seekg(at);
  const char byte = static_cast<char>(io.get());
  io.seekp(at);
  io.put(static_cast<char>(byte ^ 0x10));
}

TEST(WalCheckTest, AFlippedBitWithCommitsAfterItIsDamageThatJobStoreRefusesToOpen) {
  testing::TempDir dir("wal");
  CopyLiveStore(dir / "live", dir / "copy", 12);
  const fs::path wal = dir / "copy" / "jobs.sqlite-wal";
  ASSERT_GT(fs::file_size(wal), 32 + 12 * (24 + 4096)) << "the jobs are in the log";
  EXPECT_FALSE(FindWalDamage(wal)) << "an intact log";
  // A bit in the page of the third frame: SQLite would stop there and drop the jobs after it.
  FlipByte(wal, 32 + 2 * (24 + 4096) + 24 + 1000);
  const auto damage = FindWalDamage(wal);
  ASSERT_TRUE(damage);
  EXPECT_EQ(damage->bad_frame, 2);
  EXPECT_GE(damage->commits_after, 8);
  try {
    JobStore store(dir / "copy" / "jobs.sqlite");
    FAIL() << "a store whose log is damaged opened";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kDataLoss);
    const std::string message = e.what();
    EXPECT_NE(message.find("jobs.sqlite-wal is damaged: frame 2 fails its checksum, and "), std::string::npos)
        << message;
    EXPECT_NE(message.find("Backup and restore"), std::string::npos) << message;
  }
  // Moved aside as the message says: the store opens with what it held before the log.
  fs::rename(wal, dir / "copy" / "jobs.sqlite-wal.damaged");
  EXPECT_NO_THROW(JobStore(dir / "copy" / "jobs.sqlite"));
}

TEST(WalCheckTest, ATornEndIsACrashNotDamage) {
  testing::TempDir dir("wal");
  CopyLiveStore(dir / "live", dir / "copy", 6);
  const fs::path wal = dir / "copy" / "jobs.sqlite-wal";
  // The last frame written in part (a crash mid-write): what SQLite takes for the log's end.
  fs::resize_file(wal, fs::file_size(wal) - 2000);
  EXPECT_FALSE(FindWalDamage(wal));
  FlipByte(wal, fs::file_size(wal) - 100);  // a bit in that last frame too
  EXPECT_FALSE(FindWalDamage(wal));
  JobStore store(dir / "copy" / "jobs.sqlite");
  EXPECT_TRUE(store.Get("job-4").has_value()) << "the commits before the torn end are kept";
  EXPECT_FALSE(FindWalDamage(dir / "missing-wal"));
}

}  // namespace
}  // namespace endorecon::server
