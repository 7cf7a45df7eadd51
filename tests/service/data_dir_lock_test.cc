// One server per data folder (found by a new operator, 2026-12-05: a second server on the same
// folder started, recovered the first one's queue and ran its jobs too).
#include "server/data_dir_lock.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <optional>
#include <string>

#include "tests/unit/clip_fixture.h"
#include "tests/unit/temp_dir.h"

namespace endorecon::server {
namespace {

TEST(DataDirLockTest, ASecondServerOnTheSameFolderIsRefusedUntilTheFirstEnds) {
  testing::TempDir dir("data");
  std::optional<DataDirLock> first(std::in_place, dir.path());
  const std::string message =
      testing::ErrorFrom([&] { DataDirLock second(dir.path()); }, ErrorCode::kFailedPrecondition);
  EXPECT_NE(message.find("another endorecon-server (process " + std::to_string(::getpid()) + ") uses the data folder " +
                         dir.path().string()),
            std::string::npos)
      << message;
  first.reset();
  EXPECT_NO_THROW(DataDirLock again(dir.path()));
}

}  // namespace
}  // namespace endorecon::server
