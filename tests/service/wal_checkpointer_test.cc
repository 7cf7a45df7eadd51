#include "server/wal_checkpointer.h"

#include <gtest/gtest.h>
#include <sqlite3.h>

#include <chrono>
#include <filesystem>
#include <string>
#include <thread>

#include "server/sqlite_statement.h"
#include "tests/unit/temp_dir.h"

namespace endorecon::server {
namespace {

namespace fs = std::filesystem;

constexpr const char* kStore = "test store";

// A writer connection with one table of 4 KiB rows: a commit of one row is at least one log page.
class WalCheckpointerTest : public ::testing::Test {
 protected:
  void SetUp() override {
    file_ = dir_.path() / "test.sqlite";
    writer_ = OpenDatabase(file_, kStore);
    Exec(writer_, "CREATE TABLE rows (id INTEGER PRIMARY KEY, data BLOB NOT NULL)", kStore);
  }
  void TearDown() override { sqlite3_close(writer_); }

  void CommitRows(int rows) {
    for (int i = 0; i < rows; ++i) {
      Statement insert(writer_, "INSERT INTO rows(data) VALUES(?)", kStore);
      insert.Bind(1, std::string(4096, static_cast<char>('a' + i % 26)));
      insert.Step();
    }
  }
  std::uintmax_t DatabaseBytes() const { return fs::file_size(file_); }

  testing::TempDir dir_;
  fs::path file_;
  sqlite3* writer_ = nullptr;
};

TEST_F(WalCheckpointerTest, CommitsNoLongerCheckpointThemselves) {
  // Past SQLite's automatic mark (1,000 log pages) with a checkpointer that is never due: nothing
  // reaches the database file, so no commit ran a checkpoint.
  const auto before = DatabaseBytes();
  {
    WalCheckpointer checkpointer(file_, writer_, kStore, /*pages=*/1 << 30);
    CommitRows(1200);
    EXPECT_EQ(checkpointer.checkpoints(), 0u);
    EXPECT_EQ(DatabaseBytes(), before);
  }
  Statement count(writer_, "SELECT COUNT(*) FROM rows", kStore);
  ASSERT_TRUE(count.Step());
  EXPECT_EQ(count.Int(0), 1200);
}

TEST_F(WalCheckpointerTest, ItsThreadCopiesTheLogIntoTheDatabase) {
  WalCheckpointer checkpointer(file_, writer_, kStore, /*pages=*/16);
  CommitRows(200);
  // The thread runs beside the commits; wait for it to catch up with the last one.
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while (DatabaseBytes() < 150u * 4096 && std::chrono::steady_clock::now() < deadline) {
    CommitRows(16);  // keeps asking: the last checkpoint may have run before the last commits
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  EXPECT_GE(checkpointer.checkpoints(), 1u);
  EXPECT_GE(DatabaseBytes(), 150u * 4096);
}

}  // namespace
}  // namespace endorecon::server
