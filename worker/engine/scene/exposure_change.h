// How much a clip's exposure changes from frame to frame: for each pair of neighbouring frames (in
// the order given), the median over pixels of log((b + 1) / (a + 1)) per colour channel, a whole-frame
// gain showing as a shift of that median while motion and noise scatter around it; the pair's change
// is its largest channel's |median| less three of the median's standard errors (from the spread:
// what the pixels' noise, motion and count leave uncertain; a channel of under 16 pixels is left
// out), and the clip's the median over pairs. Pixels where either frame is near black or white
// (clipped) or shows a tool are left out; a lattice of pixels is enough.
#pragma once

#include <vector>

#include "worker/engine/scene/clip.h"

namespace endorecon::scene {

// 0 with fewer than two frames (or no usable pixel).
double ExposureChange(const Clip& clip, const std::vector<int>& frames);

}  // namespace endorecon::scene
