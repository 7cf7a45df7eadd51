// The folders that hold patient data are their owner's alone (found by a new operator, 2026-12-05:
// the server's data folder and its job store, which holds patients' names, were readable by every
// local user).
#include "common/private_folder.h"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <filesystem>

#include "common/error.h"
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

// `--data-dir` naming a file said "cannot create the folder ...: File exists".
TEST(PrivateFolderTest, AFileWhereTheFolderOrItsParentShouldBeIsNamed) {
  testing::TempDir dir("private");
  testing::WriteBytes(dir / "jobs.db", "a file");
  const auto message = [](const fs::path& path) {
    try {
      MakePrivateFolder(path);
    } catch (const Error& error) {
      EXPECT_EQ(error.code(), ErrorCode::kInvalidArgument);
      return std::string(error.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message(dir / "jobs.db").find("jobs.db as a folder: it is a file, not a folder"),
            std::string::npos)
      << message(dir / "jobs.db");
  const std::string below = message(dir / "jobs.db" / "data" / "more");
  EXPECT_NE(below.find((dir / "jobs.db").string() + " is a file, not a folder"), std::string::npos) << below;
}

}  // namespace
}  // namespace endorecon
