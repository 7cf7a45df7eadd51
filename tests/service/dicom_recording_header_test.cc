// A job's recording options against a recording's shape (common/dicom/recording_header.h): a size of
// another shape is refused with a suggestion that is itself taken.
#include "common/dicom/recording_header.h"

#include <gtest/gtest.h>

#include <regex>
#include <string>

#include "common/error.h"
#include "tests/unit/clip_fixture.h"

namespace endorecon::dicom {
namespace {

// The suggestion of an awkward shape: 64 wide for 48x32 rounds to 64x42, 1.6% off, which was
// suggested and then refused in turn (found 2026-12-07).
TEST(DicomRecordingHeaderTest, ASizeOfAnotherShapeSuggestsOneThatIsTaken) {
  const std::string refused = testing::ErrorFrom([] { CheckSameShape({64, 64}, {48, 32}); });
  EXPECT_NE(refused.find("size 64x64 changes the recording's 48x32 aspect ratio; give a size of the same "
                         "shape, e.g. 66x44"),
            std::string::npos)
      << refused;
  const std::regex suggestion(R"(e\.g\. (\d+)x(\d+))");
  for (const FrameSize recorded : {FrameSize{48, 32}, FrameSize{64, 36}, FrameSize{1917, 1079},
                                   FrameSize{101, 77}, FrameSize{33, 49}}) {
    for (const int width : {2, 4, 64, 100, 642, 2000}) {
      const FrameSize asked{width, width};
      std::string message;
      try {
        CheckSameShape(asked, recorded);
        continue;  // a square recording's square size
      } catch (const Error& e) {
        message = e.what();
      }
      std::smatch match;
      ASSERT_TRUE(std::regex_search(message, match, suggestion)) << message;
      const FrameSize suggested{std::stoi(match[1]), std::stoi(match[2])};
      EXPECT_EQ(suggested.width % 2, 0) << message;
      EXPECT_EQ(suggested.height % 2, 0) << message;
      EXPECT_NO_THROW(CheckSameShape(suggested, recorded)) << message;
    }
  }
  EXPECT_NO_THROW(CheckSameShape({}, {48, 32}));  // none asked: as recorded
}

// Frames of 4200x4200 were uploaded, queued and decoded, then refused naming the worker's own
// "clip-from-dicom/transforms.json" and no --size (found 2026-12-07): refused at submit, with a size
// that is itself taken.
TEST(DicomRecordingHeaderTest, FramesTooLargeForAClipAskForASize) {
  const std::string refused = testing::ErrorFrom([] { CheckFrameFits({}, {4200, 4200}, "huge.dcm"); });
  EXPECT_NE(refused.find("huge.dcm: frames of 4200x4200 (17640000 pixels) are larger than a clip's frame may "
                         "be (16777216 pixels, 4096 x 4096); give --size to scale them, e.g. --size "),
            std::string::npos)
      << refused;
  const std::regex suggestion(R"(--size (\d+)x(\d+))");
  for (const FrameSize recorded : {FrameSize{4200, 4200}, FrameSize{7680, 4320}, FrameSize{5101, 3401}}) {
    const std::string message = testing::ErrorFrom([&] { CheckFrameFits({}, recorded, "r.dcm"); });
    std::smatch match;
    ASSERT_TRUE(std::regex_search(message, match, suggestion)) << message;
    const FrameSize suggested{std::stoi(match[1]), std::stoi(match[2])};
    EXPECT_LE(double(suggested.width) * suggested.height, kMostFramePixels) << message;
    EXPECT_NO_THROW(CheckSameShape(suggested, recorded)) << message;
    EXPECT_NO_THROW(CheckFrameFits(suggested, recorded, "r.dcm"));
  }
  EXPECT_NO_THROW(CheckFrameFits({}, {4096, 4096}, "r.dcm"));
}

}  // namespace
}  // namespace endorecon::dicom
