#include "common/dicom/recording_layout.h"

#include <gtest/gtest.h>

#include "common/error.h"

namespace endorecon::dicom {
namespace {

TEST(RecordingLayoutTest, EachWordReadsBackAndAnUnknownOneIsRefusedNamingIt) {
  for (const auto layout :
       {StereoLayout::kMono, StereoLayout::kSideBySide, StereoLayout::kTopBottom, StereoLayout::kTwoSeries})
    EXPECT_EQ(ParseStereoLayout(StereoLayoutName(layout)), layout);
  EXPECT_EQ(ParseStereoLayout(""), StereoLayout::kMono);
  for (const auto endoscope : {Endoscope::kMoving, Endoscope::kFixed})
    EXPECT_EQ(ParseEndoscope(EndoscopeName(endoscope)), endoscope);
  EXPECT_EQ(ParseEndoscope(""), Endoscope::kMoving);
  try {
    ParseStereoLayout("diagonal");
    ADD_FAILURE() << "diagonal was taken";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
    EXPECT_NE(std::string(e.what()).find("'diagonal'"), std::string::npos) << e.what();
  }
  EXPECT_THROW(ParseEndoscope("wobbly"), Error);
}

}  // namespace
}  // namespace endorecon::dicom
