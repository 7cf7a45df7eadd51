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

// Names travel as protobuf strings, which must be UTF-8: a name of other bytes failed the upload query
// with an empty INTERNAL error (found 2026-12-05).
TEST(SafePathTest, ANameMustBeUtf8) {
  EXPECT_NO_THROW(CheckRelativePath("images/caf\xc3\xa9.png"));
  EXPECT_NO_THROW(CheckRelativePath("\xe6\x97\xa5/\xf0\x9f\x98\x80.png"));
  for (const std::string& bad :
       {std::string("images/\xff\xfe.txt"), std::string("a\xc3"), std::string("\xc0\xaf"),
        std::string("\xed\xa0\x80"), std::string("\xf4\x90\x80\x80"), std::string("\xe2\x82")}) {
    try {
      CheckRelativePath(bad);
      ADD_FAILURE() << "accepted a name that is not UTF-8";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("is not UTF-8 text"), std::string::npos) << e.what();
    }
  }
  try {
    CheckRelativePath("images/\xff\xfe.txt");
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("'images/\\xff\\xfe.txt'"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace endorecon
