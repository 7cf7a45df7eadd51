// The preview a prepared clip carries (preview.png): one frame, its depth and its mask side by side,
// so a glance shows whether rectification, depth and masks line up.
#pragma once

#include <opencv2/core.hpp>

namespace endorecon::prepare {

// Left: the frame (BGR). Middle: depth through the inferno colour map from `near` (dark) to
// `far` (bright), unknown depth black. Right: the frame with excluded pixels (`excluded`, 0/255, or
// empty) tinted blue. The whole at most 360 pixels high.
cv::Mat PreviewImage(const cv::Mat& frame, const cv::Mat& depth, const cv::Mat& excluded, double near,
                     double far);

}  // namespace endorecon::prepare
