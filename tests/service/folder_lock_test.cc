// One server per data folder (found by a new operator, 2026-12-05: a second server on the same
// folder started, recovered the first one's queue and ran its jobs too).
#include "common/folder_lock.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <optional>
#include <string>

#include "tests/unit/clip_fixture.h"
#include "tests/unit/temp_dir.h"

namespace endorecon {
namespace {

TEST(FolderLockTest, ASecondServerOnTheSameFolderIsRefusedUntilTheFirstEnds) {
  testing::TempDir dir("data");
  std::optional<FolderLock> first(std::in_place, dir.path(), "server.lock", "endorecon-server",
                                  "data folder");
  const std::string message = testing::ErrorFrom(
      [&] { FolderLock second(dir.path(), "server.lock", "endorecon-server", "data folder"); },
      ErrorCode::kFailedPrecondition);
  EXPECT_NE(message.find("another endorecon-server (process " + std::to_string(::getpid()) +
                         ") uses the data folder " + dir.path().string()),
            std::string::npos)
      << message;
  EXPECT_FALSE(LockAbandoned(dir / "server.lock")) << "held";
  first.reset();
  EXPECT_TRUE(LockAbandoned(dir / "server.lock"));
  EXPECT_FALSE(LockAbandoned(dir / "no.lock"));
  EXPECT_NO_THROW(FolderLock again(dir.path(), "server.lock", "endorecon-server", "data folder"));
}

}  // namespace
}  // namespace endorecon
