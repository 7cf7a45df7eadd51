// How the results' evaluation renders each frame within the time it may take (by default a quarter
// of the run: the time budget names the whole job, and evaluation is not its main work). A frame is
// rendered one of two ways:
//  - full: K dropout passes at every pixel (the K-pass mean colour and depth, full-resolution
//    uncertainty maps). Every held-out frame is (unless the run's budget cannot afford it:
//    HeldOut), and as many training frames as the time allows, spread evenly over the clip;
//  - reduced: one dropout-off pass at every pixel for colour and depth, and the K passes at every
//    s-th pixel of every s-th row for the uncertainty maps, upsampled (strided_map.h).
// The costs come from the field being evaluated (MeasureRenderCost), not from constants.
#pragma once

#include <string>
#include <vector>

#include "worker/engine/render/frame_renderer.h"
#include "worker/engine/scene/camera.h"

namespace endorecon::eval {

// Rendering seconds per pixel.
struct RenderCost {
  double full = 0;   // K dropout passes
  double plain = 0;  // one dropout-off pass
  bool known() const { return full > 0 && plain > 0; }
};

enum class FrameRender { kFull, kReduced };

struct EvalPlan {
  std::vector<FrameRender> frames;  // one per frame of the clip; empty: every frame full
  int stride = 2;                   // uncertainty stride of the reduced frames
  double seconds = 0;               // rendering seconds the plan is predicted to take
  RenderCost cost;                  // what it was priced with
  bool all_full() const;
  FrameRender at(int frame) const { return frames.empty() ? FrameRender::kFull : frames[frame]; }
};

// Predicted seconds to render one frame of `pixels` pixels.
double FrameSeconds(FrameRender how, int stride, const RenderCost& cost, int pixels);

// Stride 8 only where its grid keeps at least this many points a frame: the demo clip's stride-2 grid
// (160 x 128 / 4), on which the reduced maps were measured to rank as the full ones
// (docs/benchmarks.md, "The budget is the job"); from 640 x 512 frames on.
inline constexpr int kMinStridedPoints = 160 * 128 / 4;

// The strides a reduced frame's uncertainty may take on frames of `pixels` pixels, finest first: 2 and
// 4, and 8 where its grid keeps kMinStridedPoints.
std::vector<int> UncertaintyStrides(int pixels);

// What PlanEvaluation may do with held-out frames.
enum class HeldOut {
  kFull,       // always full, even when they alone overrun
  kMayReduce,  // reduced too when full ones do not fit beside the rest reduced: the run's deadline
               // comes first (a budget too small for the clip's frames)
};

// The plan that fits `seconds_available`: every frame full when that fits, when the cost is not known,
// or with seconds_available <= 0 (no limit); else every held-out frame full, the training frames
// reduced with stride 2 (4 when 2 does not fit, 8 when 4 does not and the frame is large enough:
// kMinStridedPoints) and as many of them full as the rest of the time allows, evenly spread.
// When even that does not fit, held-out frames stay full (HeldOut::kFull), or (kMayReduce) every
// frame is reduced at the coarsest stride and as many held-out frames as the time allows, evenly
// spread, are full.
EvalPlan PlanEvaluation(int frame_count, const std::vector<int>& heldout, int pixels, const RenderCost& cost,
                        double seconds_available, HeldOut held_out = HeldOut::kFull);

// Seconds of the leanest plan that keeps every held-out frame full: those full, the training frames
// reduced at the coarsest stride (UncertaintyStrides). 0 when the cost is not known.
double LeastEvaluationSeconds(int frame_count, const std::vector<int>& heldout, int pixels,
                              const RenderCost& cost);

// The time budget, rounded up to the next 10 s, of which evaluating in `least_s` and writing in
// `tail_s` would be `share`: what to ask for when a clip's results cost more than their share of a
// budget (training then gives way; reconstruct.cc).
double BudgetForEvaluationShare(double least_s, double tail_s, double share);

// One frame's render: how, and a reduced frame's uncertainty stride.
struct FrameChoice {
  FrameRender how = FrameRender::kFull;
  int stride = 2;
};

// Keeps an evaluation to its deadline when the plan's prices prove wrong (they come from a few
// tenths of a second of rendering). Before each frame it picks the costliest render the frame may
// take such that it and the frames after it end within the seconds left: a training frame as planned,
// or reduced when planned full, or coarser (UncertaintyStrides); a held-out frame full (even when
// planned reduced, if the frames run ahead), else reduced, and only once the training frames after
// it at their cheapest would not make up the time. Without a deadline or known prices, the plan.
// The pace of each kind follows the frames done so far: the last one's whole seconds (its render, its
// measures and maps, the wait for the previous frame's files) over its render's price.
class FramePacer {
 public:
  // heldout_slack_s: how far past the deadline a held-out frame may run full (the overrun a budget
  // tolerates) before it gives way.
  FramePacer(const EvalPlan& plan, std::vector<int> heldout, int pixels, bool can_reduce,
             double heldout_slack_s = 0);

  // seconds_left: until the deadline (infinity: none).
  FrameChoice Choose(int f, double seconds_left) const;
  void Rendered(FrameChoice choice, double seconds);

 private:
  double Price(FrameChoice choice) const;
  FrameChoice Planned(int f) const;
  bool IsHeldOut(int f) const;

  const EvalPlan& plan_;
  std::vector<int> heldout_;
  int pixels_;
  bool can_reduce_;
  double heldout_slack_s_;
  std::vector<int> strides_;
  double pace_[2] = {1, 1};  // seconds taken over seconds priced, per FrameRender
};

// Times both renderers on `samples` pixels of one view spread over the image (a few tenths of a second
// on a 2-core machine at the default 2,048), to price a plan on the field as it is now.
RenderCost MeasureRenderCost(render::FrameRenderer& full, render::FrameRenderer& plain,
                             const scene::Camera& camera, float time, int samples = 2048);

}  // namespace endorecon::eval
