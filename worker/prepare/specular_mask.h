// Specular highlights: the wet tissue's mirror reflections of the endoscope's light. They move
// with the viewpoint, so the two eyes see them at different places and stereo matching there is
// wrong; their depth is left unknown.
#pragma once

#include <opencv2/core.hpp>

namespace endorecon::prepare {

// 255 where an 8-bit BGR image is whitish and bright (every channel at least `min_channel`: tissue
// is red, a highlight adds white), grown by `grow` pixels to cover the highlight's halo; 0 elsewhere.
cv::Mat SpecularMask(const cv::Mat& bgr, int min_channel = 200, int grow = 2);

}  // namespace endorecon::prepare
