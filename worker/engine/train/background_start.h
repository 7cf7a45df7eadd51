// Where a learned background starts (field/background.h): what the training frames show at their
// edges. In an object capture the frame's border is mostly the backdrop, so a least-squares fit of
// the background's spherical harmonics (in logit space) to the border pixels along their rays starts
// the background near the backdrop. Started at grey instead, the field paints the backdrop on the
// far walls of its box before the background learns it (docs/benchmarks.md, "A learned background").
#pragma once

#include <vector>

#include "worker/engine/scene/clip.h"

namespace endorecon::train {

// Writes field::kBackgroundParams coefficients to params: the ridge-regularised fit of logit(colour)
// over the outermost ring of pixels of `frames` (colours clamped to [0.02, 0.98]), by least squares
// reweighted toward an L1 fit (the object may reach the frame's edge).
void FitBackgroundToBorders(const scene::Clip& clip, const std::vector<int>& frames, float* params);

}  // namespace endorecon::train
