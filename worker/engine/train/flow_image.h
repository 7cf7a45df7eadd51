// A clip's frame as optical flow sees it (train/flow_start.h and train/still_clip.h): grey, averaged
// down to the flow's size, its mean scaled to a reference's (a flickering light or an auto exposure
// breaks DIS's brightness constancy), and where a pixel may be followed (no tool in it, not
// saturated: specular highlights move with the light).
#pragma once

#include <opencv2/core.hpp>

#include "worker/engine/scene/clip.h"

namespace endorecon::train {

// OpenCV's DIS flow refuses images under this many pixels a side (an assertion, which ended a run on
// a clip `synth` makes at 8 x 8, 2026-12-05): such frames get no flow.
inline constexpr int kLeastFlowSide = 12;

struct FlowImage {
  cv::Mat grey;    // CV_8U
  cv::Mat usable;  // CV_8U, 1 or 0
};

// Frame f at `size`, its mean brought to `mean` (0: as it is).
FlowImage FlowImageOf(const scene::Clip& clip, int f, cv::Size size, double mean);

}  // namespace endorecon::train
