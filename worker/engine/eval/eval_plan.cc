#include "worker/engine/eval/eval_plan.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <utility>
#include <vector>

#include "worker/engine/eval/strided_map.h"

namespace endorecon::eval {

bool EvalPlan::all_full() const {
  return std::all_of(frames.begin(), frames.end(), [](FrameRender r) { return r == FrameRender::kFull; });
}

double FrameSeconds(FrameRender how, int stride, const RenderCost& cost, int pixels) {
  if (how == FrameRender::kFull) return cost.full * pixels;
  return (cost.plain + cost.full / double(stride * stride)) * pixels;
}

std::vector<int> UncertaintyStrides(int pixels) {
  std::vector<int> strides = {2, 4};
  if (pixels / 64 >= kMinStridedPoints) strides.push_back(8);
  return strides;
}

namespace {

// Marks `count` of `frames` full (FrameRender::kFull), evenly spread over them.
void PromoteEvenly(const std::vector<int>& frames, int count, EvalPlan& plan) {
  for (int i = 0; i < count; ++i) {
    plan.frames[frames[std::size_t((i + 0.5) * double(frames.size()) / count)]] = FrameRender::kFull;
  }
}

// How many frames each `gain` seconds dearer fit into `seconds` (clamped to [0, most] as a double: far
// behind time with a tiny gain the count is -1e12, which no int holds).
int FitCount(double seconds, double gain, std::size_t most) {
  return int(std::clamp(std::floor(seconds / std::max(gain, 1e-12)), 0.0, double(most)));
}

}  // namespace

EvalPlan PlanEvaluation(int frame_count, const std::vector<int>& heldout, int pixels, const RenderCost& cost,
                        double seconds_available, HeldOut held_out) {
  EvalPlan plan;
  plan.cost = cost;
  plan.frames.assign(frame_count, FrameRender::kFull);
  plan.stride = 2;  // for frames the evaluation reduces when it runs late
  const double all_full = frame_count * FrameSeconds(FrameRender::kFull, 1, cost, pixels);
  plan.seconds = all_full;
  if (!cost.known() || seconds_available <= 0 || all_full <= seconds_available) return plan;

  std::vector<int> train;
  for (int f = 0; f < frame_count; ++f) {
    if (std::find(heldout.begin(), heldout.end(), f) == heldout.end()) train.push_back(f);
  }
  const double full = FrameSeconds(FrameRender::kFull, 1, cost, pixels);
  const std::vector<int> strides = UncertaintyStrides(pixels);
  for (int stride : strides) {
    const double reduced = FrameSeconds(FrameRender::kReduced, stride, cost, pixels);
    const double base = double(heldout.size()) * full + double(train.size()) * reduced;
    const bool last = stride == strides.back();
    if (base > seconds_available && !last) continue;
    plan.stride = stride;
    for (int f : train) plan.frames[f] = FrameRender::kReduced;
    if (base > seconds_available && held_out == HeldOut::kMayReduce && !heldout.empty()) {
      // Every frame reduced, and held-out frames promoted back to full with the time left.
      const double all_reduced = double(frame_count) * reduced;
      const int promoted = FitCount(seconds_available - all_reduced, full - reduced, heldout.size());
      for (int f : heldout) plan.frames[f] = FrameRender::kReduced;
      PromoteEvenly(heldout, promoted, plan);
      plan.seconds = all_reduced + promoted * (full - reduced);
      return plan;
    }
    // Training frames promoted to full with the time left, evenly spread over the training frames.
    const int promoted = FitCount(seconds_available - base, full - reduced, train.size());
    PromoteEvenly(train, promoted, plan);
    plan.seconds = base + promoted * (full - reduced);
    return plan;
  }
  return plan;  // not reached: the last stride always returns
}

double LeastEvaluationSeconds(int frame_count, const std::vector<int>& heldout, int pixels,
                              const RenderCost& cost) {
  if (!cost.known()) return 0;
  const double held =
      double(std::count_if(heldout.begin(), heldout.end(), [&](int f) { return f >= 0 && f < frame_count; }));
  return held * FrameSeconds(FrameRender::kFull, 1, cost, pixels) +
         (frame_count - held) *
             FrameSeconds(FrameRender::kReduced, UncertaintyStrides(pixels).back(), cost, pixels);
}

double BudgetForEvaluationShare(double least_s, double tail_s, double share) {
  return 10 * std::ceil((least_s + tail_s) / share / 10);
}

FramePacer::FramePacer(const EvalPlan& plan, std::vector<int> heldout, int pixels, bool can_reduce,
                       double heldout_slack_s)
    : plan_(plan),
      heldout_(std::move(heldout)),
      pixels_(pixels),
      can_reduce_(can_reduce),
      heldout_slack_s_(heldout_slack_s),
      strides_(UncertaintyStrides(pixels)) {}

FrameChoice FramePacer::Planned(int f) const { return {plan_.at(f), plan_.stride}; }

double FramePacer::Price(FrameChoice choice) const {
  return pace_[int(choice.how)] * FrameSeconds(choice.how, choice.stride, plan_.cost, pixels_);
}

bool FramePacer::IsHeldOut(int f) const {
  return std::find(heldout_.begin(), heldout_.end(), f) != heldout_.end();
}

FrameChoice FramePacer::Choose(int f, double seconds_left) const {
  const FrameChoice planned = Planned(f);
  if (!can_reduce_ || !std::isfinite(seconds_left) || !plan_.cost.known() || plan_.frames.empty())
    return planned;
  const bool heldout = IsHeldOut(f);
  const FrameChoice cheapest{FrameRender::kReduced, strides_.back()};
  // The frames after this one: as planned when choosing a training frame's render; when choosing a
  // held-out frame's, the training frames at their cheapest (they give way first) and the held-out
  // ones full.
  double rest = 0;
  for (int g = f + 1; g < int(plan_.frames.size()); ++g) {
    if (!heldout) {
      rest += Price(Planned(g));
    } else {
      rest += Price(IsHeldOut(g) ? FrameChoice{FrameRender::kFull, plan_.stride} : cheapest);
    }
  }
  // The frame's renders, costliest first: full for a held-out frame (even one planned reduced, when
  // the frames run ahead of their prices) or one planned full, then reduced at the plan's stride and
  // coarser.
  std::vector<FrameChoice> options;
  if (heldout || planned.how == FrameRender::kFull) options.push_back({FrameRender::kFull, plan_.stride});
  for (int stride : strides_) {
    if (stride >= plan_.stride) options.push_back({FrameRender::kReduced, stride});
  }
  const double left = heldout ? seconds_left + heldout_slack_s_ : seconds_left;
  for (const FrameChoice& option : options) {
    if (Price(option) + rest <= left) return option;
  }
  return options.back();
}

void FramePacer::Rendered(FrameChoice choice, double seconds) {
  const double priced = FrameSeconds(choice.how, choice.stride, plan_.cost, pixels_);
  if (priced > 0) pace_[int(choice.how)] = seconds / priced;
}

RenderCost MeasureRenderCost(render::FrameRenderer& full, render::FrameRenderer& plain,
                             const scene::Camera& camera, float time, int samples) {
  const std::vector<int> picked =
      StridedPixels(camera.width, camera.height, StrideFor(camera.width, camera.height, samples));
  const int n = int(picked.size());
  std::vector<float> rgb(3 * std::size_t(n)), depth(n), opacity(n), u(n), a(n), e(n);
  const auto time_it = [&](render::FrameRenderer& renderer, const render::PixelOutputs& out) {
    const auto start = std::chrono::steady_clock::now();
    renderer.RenderPixels(camera, time, picked.data(), n, out);
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() / n;
  };
  RenderCost cost;
  cost.full = time_it(full, {rgb.data(), depth.data(), opacity.data(), u.data(), a.data(), e.data()});
  cost.plain = time_it(plain, {rgb.data(), depth.data(), opacity.data()});
  return cost;
}

}  // namespace endorecon::eval
