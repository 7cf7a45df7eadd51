// Which pixels of a frame the evaluation leaves out: the tool's.
#pragma once

#include <cstdint>
#include <vector>

#include "worker/engine/scene/clip.h"

namespace endorecon::eval {

// Tool mask a frame is evaluated with: gt_masks/ when present (EndoNeRF's evaluation), else masks/,
// else none (empty).
const std::vector<std::uint8_t>& EvaluationMask(const scene::Clip& clip, int frame);

}  // namespace endorecon::eval
