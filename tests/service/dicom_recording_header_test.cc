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

}  // namespace
}  // namespace endorecon::dicom
