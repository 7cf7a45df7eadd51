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

EvalPlan PlanEvaluation(int frame_count, const std::vector<int>& heldout, int pixels, const RenderCost& cost,
                        double seconds_available) {
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
    if (base > seconds_available && stride != strides.back()) continue;
    // Training frames promoted to full with the time left, evenly spread over the training frames.
    // Clamped as a double: far behind time with a tiny gain the count is -1e12 (no int holds it).
    const double gain = std::max(full - reduced, 1e-12);
    const int promoted =
        int(std::clamp(std::floor((seconds_available - base) / gain), 0.0, double(train.size())));
    for (int f : train) plan.frames[f] = FrameRender::kReduced;
    for (int i = 0; i < promoted; ++i) {
      plan.frames[train[std::size_t((i + 0.5) * double(train.size()) / promoted)]] = FrameRender::kFull;
    }
    plan.stride = stride;
    plan.seconds = base + promoted * (full - reduced);
    return plan;
  }
  return plan;  // not reached: the last stride always returns
}

FramePacer::FramePacer(const EvalPlan& plan, std::vector<int> heldout, int pixels, bool can_reduce)
    : plan_(plan),
      heldout_(std::move(heldout)),
      pixels_(pixels),
      can_reduce_(can_reduce),
      strides_(UncertaintyStrides(pixels)) {}

FrameChoice FramePacer::Planned(int f) const { return {plan_.at(f), plan_.stride}; }

double FramePacer::Price(FrameChoice choice) const {
  return pace_[int(choice.how)] * FrameSeconds(choice.how, choice.stride, plan_.cost, pixels_);
}

FrameChoice FramePacer::Choose(int f, double seconds_left) const {
  const FrameChoice planned = Planned(f);
  const bool heldout = std::find(heldout_.begin(), heldout_.end(), f) != heldout_.end();
  if (!can_reduce_ || !std::isfinite(seconds_left) || !plan_.cost.known() || plan_.frames.empty() || heldout)
    return planned;
  double rest = 0;
  for (int g = f + 1; g < int(plan_.frames.size()); ++g) rest += Price(Planned(g));
  // The frame's renders, costliest first.
  std::vector<FrameChoice> options;
  if (planned.how == FrameRender::kFull) options.push_back(planned);
  for (int stride : strides_) {
    if (stride >= plan_.stride) options.push_back({FrameRender::kReduced, stride});
  }
  for (const FrameChoice& option : options) {
    if (Price(option) + rest <= seconds_left) return option;
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
