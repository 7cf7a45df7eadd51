// A worker killed -9 mid-job leaves the job's folder in its scratch (found by bench/fault_campaign):
// the next start removes such folders and nothing else.
#include <gtest/gtest.h>

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

}  // namespace
}  // namespace endorecon::worker
