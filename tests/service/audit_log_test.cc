#include "server/audit_log.h"

#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/stat.h>

#include <csignal>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>

#include "common/error.h"
#include "tests/unit/temp_dir.h"

namespace endorecon::server {
namespace {

TEST(AuditLogTest, OneJsonLinePerEntryFromManyThreadsAndWriters) {
  testing::TempDir dir("audit");
  const auto path = dir / "audit.jsonl";
  {
    AuditLog first(path);
    AuditLog second(path);  // another process appending (endorecon-server token ...)
    std::vector<std::thread> threads;
    for (int t = 0; t < 4; ++t) {
      threads.emplace_back([&, t] {
        for (int i = 0; i < 50; ++i) {
          (t % 2 ? first : second)
              .Write({"alice", "client", "radiology", "Submit", "job" + std::to_string(i), "OK",
                      "ipv4:127.0.0.1:1", "", ""});
        }
      });
    }
    for (auto& thread : threads) thread.join();
    first.Write({"-", "-", "", "List", "", "UNAUTHENTICATED", "ipv4:127.0.0.1:2", "worker-1", "bad\xff"});
  }
  std::istringstream text(testing::ReadBytes(path));
  int lines = 0;
  nlohmann::json last;
  for (std::string line; std::getline(text, line); ++lines) last = nlohmann::json::parse(line);
  EXPECT_EQ(lines, 201);
  EXPECT_EQ(last["method"], "List");
  EXPECT_EQ(last["outcome"], "UNAUTHENTICATED");
  EXPECT_EQ(last["certificate"], "worker-1");
  EXPECT_EQ(last["time"].get<std::string>().size(), 24u);  // 2026-11-30T12:00:00.000Z
  EXPECT_EQ(last["time"].get<std::string>().back(), 'Z');
}

// A named pipe with no reader is refused at once: the server hung in open() at start, deaf to SIGTERM
// (found 2026-12-06).
TEST(AuditLogTest, APipeNoProcessReadsIsRefusedNotWaitedOn) {
  testing::TempDir dir("audit");
  ASSERT_EQ(::mkfifo((dir / "audit.fifo").c_str(), 0600), 0);
  try {
    AuditLog log(dir / "audit.fifo");
    ADD_FAILURE() << "opened a pipe no one reads";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
    EXPECT_NE(std::string(e.what()).find("a named pipe (FIFO) that no process reads"), std::string::npos)
        << e.what();
  }
}

// A mistyped --audit-log is the operator's to fix: NOT_FOUND naming the missing folder, and a folder
// refused as no file (both were UNAVAILABLE, the server's exit 1 for trouble with its disk; found
// 2026-12-07).
TEST(AuditLogTest, AMissingFolderOrAFolderIsNamed) {
  testing::TempDir dir("audit");
  try {
    AuditLog log(dir / "nowhere" / "audit.jsonl");
    ADD_FAILURE() << "opened a file in a folder that is not there";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kNotFound);
    EXPECT_NE(std::string(e.what()).find("its folder " + (dir / "nowhere").string() + " does not exist"),
              std::string::npos)
        << e.what();
  }
  testing::WriteBytes(dir / "plain", "a file");
  try {
    AuditLog log(dir / "plain" / "audit.jsonl");
    ADD_FAILURE() << "opened a file under a file";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
    EXPECT_NE(std::string(e.what()).find("plain is a file, not a folder"), std::string::npos) << e.what();
  }
  try {
    AuditLog log(dir.path());
    ADD_FAILURE() << "opened a folder";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
    EXPECT_NE(std::string(e.what()).find(": a folder; name a file in it"), std::string::npos) << e.what();
  }
}

// A line the disk refuses (/dev/full: ENOSPC on every write) is counted for the metric and its alert
// (it was only logged).
TEST(AuditLogTest, AFailedWriteIsCounted) {
  AuditLog log("/dev/full");
  int failures = 0;
  log.SetFailureObserver([&] { ++failures; });
  AuditEntry entry;
  entry.method = "Submit";
  log.Write(entry);
  log.Write(entry);
  EXPECT_EQ(failures, 2);
}

// A line the disk takes only part of (a file-size limit here, as a disk that fills mid-line) is cut
// back: the next line starts a line, and every line reads as JSON (the part line had the next glued
// to it; found 2026-12-07).
TEST(AuditLogTest, APartLineIsCutBack) {
  testing::TempDir dir("audit-part");
  AuditLog log(dir / "audit.jsonl");
  AuditEntry entry;
  entry.method = "Submit";
  log.Write(entry);
  const auto one_line = std::filesystem::file_size(dir / "audit.jsonl");
  struct rlimit before {};
  ASSERT_EQ(::getrlimit(RLIMIT_FSIZE, &before), 0);
  const auto old_handler = std::signal(SIGXFSZ, SIG_IGN);
  struct rlimit limit = before;
  limit.rlim_cur = static_cast<rlim_t>(one_line + one_line / 2);  // room for half the next line
  ASSERT_EQ(::setrlimit(RLIMIT_FSIZE, &limit), 0);
  int failures = 0;
  log.SetFailureObserver([&] { ++failures; });
  log.Write(entry);
  ASSERT_EQ(::setrlimit(RLIMIT_FSIZE, &before), 0);
  std::signal(SIGXFSZ, old_handler);
  EXPECT_EQ(failures, 1);
  EXPECT_EQ(std::filesystem::file_size(dir / "audit.jsonl"), one_line);
  entry.method = "Cancel";
  log.Write(entry);
  std::istringstream lines(testing::ReadBytes(dir / "audit.jsonl"));
  int count = 0;
  for (std::string line; std::getline(lines, line); ++count)
    EXPECT_TRUE(nlohmann::json::accept(line)) << line;
  EXPECT_EQ(count, 2);
}

}  // namespace
}  // namespace endorecon::server
