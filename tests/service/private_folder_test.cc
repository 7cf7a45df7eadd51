// The folders that hold patient data are their owner's alone (found by a new operator, 2026-12-05:
// the server's data folder and its job store, which holds patients' names, were readable by every
// local user).
#include "common/private_folder.h"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <filesystem>

#include "tests/unit/temp_dir.h"

namespace endorecon {
namespace {

namespace fs = std::filesystem;

TEST(PrivateFolderTest, AFolderAndWhatIsCreatedInItAreTheOwnersAlone) {
  testing::TempDir dir("private");
  const mode_t before = ::umask(022);
  EXPECT_FALSE(MakePrivateFolder(dir / "new" / "data")) << "created private, nothing to remove";
  EXPECT_EQ(fs::status(dir / "new" / "data").permissions() & (fs::perms::group_all | fs::perms::others_all),
            fs::perms::none);
  testing::WriteBytes(dir / "new" / "data" / "jobs.sqlite", "patients");
  EXPECT_EQ(fs::status(dir / "new" / "data" / "jobs.sqlite").permissions(),
            fs::perms::owner_read | fs::perms::owner_write);

  // An existing folder open to others is said so, and left as it is (it may be a shared one).
  fs::create_directories(dir / "old");
  fs::permissions(dir / "old", fs::perms::all);
  EXPECT_TRUE(MakePrivateFolder(dir / "old"));
  EXPECT_EQ(fs::status(dir / "old").permissions(), fs::perms::all);
  ::umask(before);
}

}  // namespace
}  // namespace endorecon
