// A worker killed -9 mid-job leaves the job's folder in its scratch (found by bench/fault_campaign):
// the next start removes such folders and nothing else.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <optional>
#include <string>

#include "common/error.h"
#include "common/folder_lock.h"
#include "tests/unit/clip_fixture.h"
#include "tests/unit/temp_dir.h"
#include "worker/runtime/job_runner.h"

namespace endorecon::worker {
namespace {

namespace fs = std::filesystem;

TEST(LeftoverJobsTest, AStartRemovesTheJobFoldersAKilledRunLeft) {
  testing::TempDir scratch("scratch");
  fs::create_directories(scratch / "2dab33cc5a41/out/model");
  testing::WriteBytes(scratch / "2dab33cc5a41/out/model/checkpoint.bin", "partial");
  fs::create_directories(scratch / "0123456789ab/clip");
  EXPECT_EQ(RemoveLeftoverJobs(scratch.path()), 2);
  EXPECT_TRUE(fs::is_empty(scratch.path()));
}

TEST(LeftoverJobsTest, AMissingScratchFolderIsNothingToRemove) {
  testing::TempDir parent("scratch");
  EXPECT_EQ(RemoveLeftoverJobs(parent / "not-yet"), 0);
}

// The default scratch folder is named by the worker's PID, so a killed worker's folder was never
// seen again (found 2026-12-05): a start removes those of this host's workers that are gone, and
// not a living worker's, another host's, or a folder of another name.
TEST(LeftoverJobsTest, AStartRemovesTheScratchFoldersOfWorkersThatAreGone) {
  testing::TempDir temp("scratch");
  const pid_t child = fork();
  if (child == 0) _exit(0);
  ASSERT_GT(child, 0);
  waitpid(child, nullptr, 0);  // gone now: its PID names no process
  const std::string dead = "endorecon-host-" + std::to_string(child);
  const std::string alive = "endorecon-host-" + std::to_string(getppid());
  for (const std::string& name : {dead, alive, std::string("endorecon-other-") + std::to_string(child),
                                  std::string("endorecon-host-gpu7")}) {
    fs::create_directories(temp / name / "2dab33cc5a41");
  }
  EXPECT_EQ(RemoveDeadWorkersFolders(temp.path(), "host"), 1);
  EXPECT_FALSE(fs::exists(temp / dead));
  EXPECT_TRUE(fs::exists(temp / alive));
  EXPECT_TRUE(fs::exists(temp / ("endorecon-other-" + std::to_string(child))));
  EXPECT_TRUE(fs::exists(temp / "endorecon-host-gpu7"));
}

// A worker with an --id of its own (/tmp/endorecon-wA) left its folder, with the clip in it, after a
// kill -9 for good: only a start with the same id removed it (found 2026-12-06). A worker holds a
// lock in its scratch folder while it runs; a folder whose lock nobody holds, a minute old, is a
// gone worker's. A second worker on the same folder is refused: its start cleared the first's jobs.
TEST(LeftoverJobsTest, AScratchFolderIsItsWorkersWhileItRunsAndRemovedAfter) {
  testing::TempDir temp("scratch");
  for (const char* name : {"endorecon-wA", "endorecon-wB", "endorecon-wC"}) {
    fs::create_directories(temp / name / "2dab33cc5a41");
  }
  std::optional<FolderLock> running(std::in_place, temp / "endorecon-wA", kWorkerLockFile, "endorecon-worker",
                                    "scratch folder");
  const std::string second = testing::ErrorFrom(
      [&] { FolderLock(temp / "endorecon-wA", kWorkerLockFile, "endorecon-worker", "scratch folder"); },
      ErrorCode::kFailedPrecondition);
  EXPECT_NE(second.find("another endorecon-worker (process " + std::to_string(getpid()) +
                        ") uses the scratch folder"),
            std::string::npos)
      << second;
  { FolderLock gone(temp / "endorecon-wB", kWorkerLockFile, "endorecon-worker", "scratch folder"); }
  const auto old = fs::file_time_type::clock::now() - std::chrono::minutes(5);
  fs::last_write_time(temp / "endorecon-wA" / kWorkerLockFile, old);
  fs::last_write_time(temp / "endorecon-wB" / kWorkerLockFile, old);
  EXPECT_EQ(RemoveDeadWorkersFolders(temp.path(), "host"), 1);
  EXPECT_TRUE(fs::exists(temp / "endorecon-wA")) << "its worker runs";
  EXPECT_FALSE(fs::exists(temp / "endorecon-wB"));
  EXPECT_TRUE(fs::exists(temp / "endorecon-wC")) << "no lock, no HOST-PID name: not known to be a worker's";
  running.reset();
  EXPECT_EQ(RemoveDeadWorkersFolders(temp.path(), "host"), 1);
  EXPECT_FALSE(fs::exists(temp / "endorecon-wA"));
}

}  // namespace
}  // namespace endorecon::worker
