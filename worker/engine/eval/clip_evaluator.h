// Renders every frame of a clip from a trained field, measures it against the clip, and writes
// the per-frame results (rgb/, depth/, pointcloud/, video.mp4, and with a renderer that estimates
// uncertainty: uncertainty/ and error/). Each frame is rendered as its plan says (eval_plan.h); a
// frame's files are written while the next frame renders. Returns the metrics as JSON.
#pragma once

#include <chrono>
#include <filesystem>
#include <functional>
#include <nlohmann/json_fwd.hpp>
#include <vector>

#include "worker/engine/eval/eval_plan.h"
#include "worker/engine/render/frame_renderer.h"
#include "worker/engine/scene/clip.h"

namespace endorecon::eval {

struct ClipEvaluation {
  std::vector<int> train_frames, heldout_frames;
  bool write_files = true;
  std::function<void(int done, int total)> on_frame;  // progress while rendering
  // How each frame is rendered (empty: every frame full). Reduced frames need `plain`, a renderer
  // of the same field without dropout passes; without it every frame is rendered full.
  EvalPlan plan;
  render::FrameRenderer* plain = nullptr;
  // When set, the frames are kept to it (FramePacer): a training frame planned full is rendered
  // reduced, and a reduced one's uncertainty coarser, once the frames left would not finish by then
  // at the pace measured so far.
  std::chrono::steady_clock::time_point deadline = std::chrono::steady_clock::time_point::max();
  double heldout_slack_s = 0;  // how far past it a held-out frame may run full (FramePacer)
  // Polled before each frame: true stops the evaluation (a cancel, a worker's shutdown), which then
  // throws Error(kCancelled) once the frame in flight is written.
  std::function<bool()> should_stop;
};

// Metrics: "train" and "heldout" splits each with per-frame and summarised image metrics (tissue
// pixels: eval masks (gt_masks/) when the clip has them, else tool masks) and depth error against
// the clip's ground-truth depth when present; "depth_png_scale". With uncertainty (renderer settings
// mc_passes > 0): each split gets "calibration" (MeasureCalibration of the total uncertainty against
// PixelRmse on tissue pixels, summarised over frames, with the mean sparsification curves), and
// "uncertainty_maps" records the heat-map scales (one per clip: the HeatmapScale bound of every
// frame's total uncertainty, error and model map; the maps go to disk frame by frame, none is kept
// until the end) and the estimator's settings. "evaluation" says
// which frames were rendered how and where the seconds went (render, write: the writing thread's
// busy time, wall).
nlohmann::json EvaluateClip(const scene::Clip& clip, render::FrameRenderer& renderer,
                            const ClipEvaluation& what, const std::filesystem::path& out_dir);

// What the uncertainty maps of a renderer mean, for metrics.json: K, lambda, eps, the score's
// formula and the error measure calibration uses.
nlohmann::json UncertaintySettings(const render::FrameRenderSettings& settings);

}  // namespace endorecon::eval
