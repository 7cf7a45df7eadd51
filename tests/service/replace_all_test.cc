#include "common/replace_all.h"

#include <gtest/gtest.h>

namespace endorecon {
namespace {

// Left to right, the replacement never searched again (a folder said as a name that holds it).
TEST(ReplaceAllTest, EveryOccurrenceOnceAndNotTheReplacement) {
  EXPECT_EQ(ReplaceAll("/w/clip/a.png and /w/clip/b.png", "/w/clip/", ""), "a.png and b.png");
  EXPECT_EQ(ReplaceAll("/w/clip: empty", "/w/clip", "the clip"), "the clip: empty");
  EXPECT_EQ(ReplaceAll("aaa", "a", "aa"), "aaaaaa");
  EXPECT_EQ(ReplaceAll("text", "", "x"), "text");
  EXPECT_EQ(ReplaceAll("none here", "clip", "x"), "none here");
}

}  // namespace
}  // namespace endorecon
