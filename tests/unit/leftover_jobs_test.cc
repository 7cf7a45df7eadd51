// A worker killed -9 mid-job leaves the job's folder in its scratch (found by bench/fault_campaign):
// the next start removes such folders and nothing else.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <string>

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

}  // namespace
}  // namespace endorecon::worker
