#include "worker/engine/eval/eval_plan.h"

#include <algorithm>
#include <chrono>
#include <cmath>
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
  std::vector<int> strides = {2, 4};
  if (pixels / 64 >= kMinStridedPoints) strides.push_back(8);
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
