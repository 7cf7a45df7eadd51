#include "common/file_read.h"

#include <gtest/gtest.h>

#include <iterator>
#include <string>

#include "common/error.h"
#include "tests/unit/temp_dir.h"

namespace endorecon {
namespace {

TEST(FileRead, OpensAFileAndSaysWhyOneCannotBeOpened) {
  testing::TempDir dir("file-read");
  testing::WriteBytes(dir / "a.json", "{}");
  std::ifstream in = OpenToRead(dir / "a.json");
  EXPECT_EQ(std::string(std::istreambuf_iterator<char>(in), {}), "{}");
  // Under a file, which no folder is: the system's reason, not "cannot open the file" alone (as root,
  // which reads every file, this is a refusal a test can make).
  try {
    OpenToRead(dir / "a.json" / "b.png");
    FAIL() << "opened a path under a file";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
    EXPECT_NE(std::string(e.what()).find("a.json/b.png: cannot open the file (Not a directory)"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace endorecon
