// The frame renderer's settings a training configuration asks for, in one place: evaluation and
// previews (EvalRenderSettings), the same with Monte Carlo uncertainty on (UncertaintyRenderSettings,
// for results and novel views), and depth refinement (its own sample counts).
#pragma once

#include <cstdint>

#include "worker/engine/render/frame_renderer.h"
#include "worker/engine/train/train_config.h"

namespace endorecon::train {

// Coarse and fine samples and the uniform floor of evaluation, over [near, far]; no uncertainty.
render::FrameRenderSettings EvalRenderSettings(const TrainConfig& config, double near, double far);

// EvalRenderSettings with K = config.mc_passes dropout passes, lambda, eps and the masks' seed.
render::FrameRenderSettings UncertaintyRenderSettings(const TrainConfig& config, double near, double far,
                                                      std::uint64_t seed);

// EvalRenderSettings with half the coarse samples (at least 8) and all the fine ones: the colour and
// depth of the results' reduced frames (eval/eval_plan.h).
render::FrameRenderSettings ReducedRenderSettings(const TrainConfig& config, double near, double far);

// EvalRenderSettings with depth_refine_samples coarse and as many fine samples.
render::FrameRenderSettings DepthRefineRenderSettings(const TrainConfig& config, double near, double far);

}  // namespace endorecon::train
