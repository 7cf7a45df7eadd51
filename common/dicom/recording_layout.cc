#include "common/dicom/recording_layout.h"

#include "common/error.h"

namespace endorecon::dicom {

StereoLayout ParseStereoLayout(const std::string& text) {
  if (text.empty() || text == "mono") return StereoLayout::kMono;
  if (text == "side-by-side") return StereoLayout::kSideBySide;
  if (text == "top-bottom") return StereoLayout::kTopBottom;
  if (text == "series") return StereoLayout::kTwoSeries;
  FailInvalid("stereo layout '" + text + "': expected mono, side-by-side, top-bottom or series");
}

Endoscope ParseEndoscope(const std::string& text) {
  if (text.empty() || text == "moving") return Endoscope::kMoving;
  if (text == "fixed") return Endoscope::kFixed;
  FailInvalid("endoscope '" + text + "': expected moving or fixed");
}

std::string EndoscopeName(Endoscope endoscope) { return endoscope == Endoscope::kFixed ? "fixed" : "moving"; }

std::string StereoLayoutName(StereoLayout layout) {
  switch (layout) {
    case StereoLayout::kSideBySide:
      return "side-by-side";
    case StereoLayout::kTopBottom:
      return "top-bottom";
    case StereoLayout::kTwoSeries:
      return "series";
    case StereoLayout::kMono:
      break;
  }
  return "mono";
}

}  // namespace endorecon::dicom
