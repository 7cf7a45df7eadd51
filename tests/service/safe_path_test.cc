#include "common/safe_path.h"

#include <gtest/gtest.h>

#include "common/error.h"

namespace endorecon {
namespace {

TEST(SafePathTest, AcceptsRelativePaths) {
  EXPECT_NO_THROW(CheckRelativePath("images/000001.png"));
  EXPECT_NO_THROW(CheckRelativePath("poses_bounds.npy"));
  EXPECT_NO_THROW(CheckRelativePath("a/..b/c.."));
}

TEST(SafePathTest, RejectsEscapesAndNamesThePath) {
  for (const std::string bad :
       {"../x", "a/../../x", "/etc/passwd", "a//b", "./a", "a/", "", "a\\b", "..", "a/.."}) {
    try {
      CheckRelativePath(bad);
      ADD_FAILURE() << "accepted '" << bad << "'";
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
      EXPECT_NE(std::string(e.what()).find("'" + bad + "'"), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace endorecon
