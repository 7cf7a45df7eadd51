// One training ray placed from its pick, as an ENDORECON_HD function over plain tables so the CPU
// trainer and the CUDA kernels place the same samples for a seed: the pixel's colour (the target), its
// depth prior (refined, train/depth_refiner.h), the camera ray and its occupied span, and the
// depth-guided samples (stratified without depth) turned into field inputs.
#pragma once

#include <cstdint>

#include "common/hd.h"
#include "worker/engine/base/counter_rng.h"
#include "worker/engine/render/camera_ray.h"
#include "worker/engine/render/depth_guided_sampler.h"
#include "worker/engine/render/stratified_sampler.h"
#include "worker/engine/scene/view_geometry.h"
#include "worker/engine/train/ray_picks.h"

namespace endorecon::train {

// What placing a training ray reads, per clip frame where it says so.
struct TrainingRayTables {
  const std::uint8_t* const* rgb = nullptr;   // per frame: H x W x 3
  const float* const* priors = nullptr;       // per frame: H x W depth priors (0 unknown); null without depth
  const scene::PinholeView* views = nullptr;  // per frame
  const float* times = nullptr;               // per frame
  scene::BoxFrame box;
  render::OccupancyView occupancy;
  double near = 0, far = 1;
  render::DepthGuidedConfig<float> guided;  // the samples around a prior: n = gaussian + stratified
};

// The ray of `pick` into ray r of the batch: target (3 values in [0, 1]), *prior (0 without depth),
// *ray (the camera ray and its span, for re-placing samples later) and n samples in `slot`, drawn from
// CounterRng(step_seed, 2r + 1).
ENDORECON_HD void PlaceTrainingRay(const TrainingRayTables& t, const RayPick& pick, std::uint64_t step_seed,
                                   int r, int n, float* target, float* prior, render::CameraRay* ray,
                                   const render::RaySlot& slot) {
  const std::uint8_t* px = t.rgb[pick.frame] + 3 * static_cast<std::size_t>(pick.pixel);
  for (int c = 0; c < 3; ++c) target[c] = px[c] / 255.0f;
  const float p = t.priors ? t.priors[pick.frame][pick.pixel] : 0.0f;
  *prior = p;
  const base::CounterRng<float> uniform(step_seed, static_cast<std::uint64_t>(2 * r + 1));
  *ray = render::CameraRayOfPixel(t.views[pick.frame], pick.pixel, t.box, t.occupancy, t.near, t.far);
  render::PlaceSamples(
      *ray, t.box, t.times[pick.frame], n,
      [&](float lo, float hi, float* s, float* delta) {
        if (t.priors) {
          render::DepthGuidedSamples(lo, hi, p, t.guided, uniform, s, delta);
        } else {
          render::StratifiedSamples(lo, hi, n, uniform, s, delta);
        }
      },
      slot);
}

}  // namespace endorecon::train
