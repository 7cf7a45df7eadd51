// The text forms of prepare's options and the checks of their combinations (worker, CLI and
// server parse them the same way).
#include "common/prepare_flags.h"

#include <gtest/gtest.h>

#include "tests/unit/clip_fixture.h"

namespace endorecon::testing {
namespace {

TEST(PrepareFlagsTest, FrameRanges) {
  const FrameRange all = ParseFrameRange("");
  EXPECT_TRUE(all.Selects(0) && all.Selects(12345));
  const FrameRange range = ParseFrameRange("5:50:5");
  EXPECT_TRUE(range.Selects(5) && range.Selects(45));
  EXPECT_FALSE(range.Selects(0) || range.Selects(6) || range.Selects(50));
  EXPECT_EQ(ParseFrameRange("10:").ToString(), "10::1");
  EXPECT_EQ(ParseFrameRange("::3").step, 3);
  for (const char* bad : {"a:b", "1:2:0", "5:5", "1:2:3:4", "-1:", "2.5:", "2", "::-1"}) {
    const std::string message = ErrorFrom([&] { ParseFrameRange(bad); });
    EXPECT_NE(message.find(std::string("'") + bad + "': expected START:END:STEP"), std::string::npos)
        << message;
  }
  // A number alone read as "frame 2" took frame 2 on (found 2026-12-06); Python's negatives are named.
  EXPECT_NE(ErrorFrom([&] { ParseFrameRange("2"); }).find("2: takes frame 2 on, 2:3 frame 2 alone"),
            std::string::npos);
  EXPECT_NE(ErrorFrom([&] {
              ParseFrameRange("-3:");
            }).find("numbers from the end (negative, as in Python) are not"),
            std::string::npos);
}

TEST(PrepareFlagsTest, SizesAndRegions) {
  EXPECT_EQ(ParseFrameSize("640x512").width, 640);
  for (const char* bad : {"641x512", "640", "0x0", "640x512x3", "x512"})
    ErrorFrom([&] { ParseFrameSize(bad); });
  // Larger than a clip's frames may be: said so, not blamed on the width's parity.
  EXPECT_EQ(ParseFrameSize("4096x4096").height, 4096);
  for (const char* big : {"6400x4800", "64000x48000"}) {
    const std::string message = ErrorFrom([&] { ParseFrameSize(big); });
    EXPECT_NE(message.find("at most 16777216 pixels a frame"), std::string::npos) << message;
  }
  const PixelRect rect = ParsePixelRect("0,700,1280,20");
  EXPECT_EQ(rect.y, 700);
  EXPECT_EQ(rect.width, 1280);
  for (const char* bad : {"1,2,3", "1,2,0,4", "a,b,c,d", "-1,0,4,4"}) ErrorFrom([&] { ParsePixelRect(bad); });
}

TEST(PrepareFlagsTest, CombinationsAreChecked) {
  PrepareFlags flags;
  flags.left = "L.mp4";
  flags.right = "R.mp4";
  flags.calibration = {"calib.yaml"};
  CheckPrepareFlags(flags);
  EXPECT_EQ(flags.Paths(), (std::vector<std::string>{"L.mp4", "R.mp4", "calib.yaml"}));

  PrepareFlags two_forms = flags;
  two_forms.side_by_side = "sbs.mp4";
  EXPECT_NE(ErrorFrom([&] { CheckPrepareFlags(two_forms); }).find("exactly one of these"), std::string::npos);
  PrepareFlags no_right = flags;
  no_right.right.clear();
  EXPECT_NE(ErrorFrom([&] { CheckPrepareFlags(no_right); }).find("--left and --right go together"),
            std::string::npos);
  PrepareFlags both_calibrations = flags;
  both_calibrations.rectified = true;
  ErrorFrom([&] { CheckPrepareFlags(both_calibrations); });
  PrepareFlags rectified = flags;
  rectified.calibration.clear();
  rectified.rectified = true;
  EXPECT_NE(ErrorFrom([&] { CheckPrepareFlags(rectified); }).find("--focal PX and --baseline B"),
            std::string::npos);
  rectified.focal = 500;
  rectified.baseline = 4;
  CheckPrepareFlags(rectified);
  PrepareFlags bad = flags;
  bad.mask_tool = "grey";
  ErrorFrom([&] { CheckPrepareFlags(bad); });
  bad = flags;
  bad.exclude = {"1,2,3"};
  ErrorFrom([&] { CheckPrepareFlags(bad); });
  bad = flags;
  bad.estimate_poses = true;
  bad.poses = "poses.json";
  ErrorFrom([&] { CheckPrepareFlags(bad); });
}

}  // namespace
}  // namespace endorecon::testing
