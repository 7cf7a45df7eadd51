// The per-ray bodies of a training step, as ENDORECON_HD functions over a batch's arrays, so the CPU
// backend (cpu_step.cc, TBB loops) and the CUDA backend (kernels) run the same math on the same seeds:
// placing a ray from its pick, the stratified probes and the re-placed samples of a guided ray
// (uncertainty-guided reallocation), the ray's loss and its gradient, and a probe ray's score for the
// uncertainty map.
#pragma once

#include <cstdint>

#include "common/hd.h"
#include "worker/engine/base/counter_rng.h"
#include "worker/engine/field/background_math.h"
#include "worker/engine/field/variance.h"
#include "worker/engine/render/adaptive_sampler.h"
#include "worker/engine/render/camera_ray.h"
#include "worker/engine/render/depth_guided_sampler.h"
#include "worker/engine/render/sample_score.h"
#include "worker/engine/render/stratified_sampler.h"
#include "worker/engine/render/volume_renderer.h"
#include "worker/engine/train/losses.h"
#include "worker/engine/train/ray_loss.h"
#include "worker/engine/train/ray_picks.h"
#include "worker/engine/train/training_ray.h"

namespace endorecon::train {

// eps of the per-ray min-max normalisation of the variances (sample_score.h).
inline constexpr float kScoreEps = 1e-6f;

// What a step's loops read, kept current by the Trainer (pointers into the clip, the sampler, the
// map, the refiner and the occupancy grid, on whichever device the backend keeps its copy).
struct StepTables {
  PickTables picks;
  MapTables map;
  TrainingRayTables rays;
  RayLossTerms terms;  // batch-normalised weights
  int frames = 0;      // of the clip (the per-frame tables' length)
  int rays_per_batch = 0;
  int samples = 0;             // per ray: depth + stratified
  int stratified_samples = 0;  // the probes of a guided ray when the clip has depth
  bool has_depth = false;
  float adaptive_floor = 0.2f;
  float uncertainty_lambda = 1;
  float variance_eps = 1e-6f;
  float background[3] = {0, 0, 0};  // what rays see past the samples (train_config.h "background")
  // The field's learned background (field/background.h), when it has one: then rays see bg(d) instead.
  const float* background_params = nullptr;
};

// A step's batch: ray-major arrays of `rays` rays with `samples` samples each (probe arrays hold a
// guided ray's probes: samples when the clip has no depth, stratified_samples otherwise).
struct StepBatch {
  int rays = 0, samples = 0;
  float *target, *prior, *s, *delta, *pos, *dir, *time;
  float *sigma, *sigma_logvar, *rgb, *rgb_logvar, *weights;
  float *d_weights, *d_sigma, *d_rgb, *d_rgb_logvar;
  float *ray_dir, *background, *d_background;  // per ray (3 each): its unit direction, bg(d), dL/d(bg)
  RayPick* picks;
  render::CameraRay* camera_rays;
  float *probe_s, *probe_delta, *probe_score;

  ENDORECON_HD render::RaySlot Slot(int r, int n) const {
    return render::RaySlotOf(s, delta, pos, dir, time, r, n);
  }
};

// Seeds of the rays of a step: picks and samples from step_seed, guided picks from step_seed ^ a
// constant (two independent streams per ray).
ENDORECON_HD std::uint64_t GuidedPickSeed(std::uint64_t step_seed) { return step_seed ^ 0x6a1dedull; }

// Ray r: guided rays (r < guided) from the map when it is ready, the others by mask importance.
ENDORECON_HD void PlaceStepRay(const StepTables& t, const StepBatch& b, int r, int guided,
                               std::uint64_t step_seed) {
  const std::uint64_t stream = static_cast<std::uint64_t>(2 * r);
  RayPick pick;
  if (!(r < guided && PickFromMap(t.map, t.picks, GuidedPickSeed(step_seed), stream, &pick))) {
    pick = PickRay(t.picks, step_seed, stream);
  }
  b.picks[r] = pick;
  PlaceTrainingRay(t.rays, pick, step_seed, r, b.samples, b.target + 3 * r, b.prior + r, b.camera_rays + r,
                   b.Slot(r, b.samples));
}

// The probes of guided ray r: m stratified samples over its span (the same draws as the stratified
// part of its ordinary samples), their points in rows [r m, (r + 1) m) of pos/dir/time.
ENDORECON_HD int ProbeCount(const StepTables& t) { return t.has_depth ? t.stratified_samples : t.samples; }

ENDORECON_HD void PlaceProbes(const StepTables& t, const StepBatch& b, int r, std::uint64_t step_seed) {
  const int m = ProbeCount(t);
  const base::CounterRng<float> uniform(step_seed, static_cast<std::uint64_t>(2 * r + 1));
  render::PlaceSamples(
      b.camera_rays[r], t.rays.box, t.rays.times[b.picks[r].frame], m,
      [&](float lo, float hi, float* s, float* delta) {
        render::StratifiedSamples(lo, hi, m, uniform, s, delta);
      },
      render::RaySlotOf(b.probe_s, b.probe_delta, b.pos, b.dir, b.time, r, m));
}

// Guided ray r, once its probes went through one dropout-on pass (outputs in rows [r m, (r + 1) m) of
// sigma/sigma_logvar/rgb_logvar): the probes' sample scores, then the ray's stratified samples re-placed
// by them with a uniform floor (all n samples without a depth prior; with one the Gaussian samples
// around it stay, the same draws as PlaceTrainingRay's), and the ray's field inputs rewritten.
ENDORECON_HD void ReallocateRay(const StepTables& t, const StepBatch& b, int r, std::uint64_t step_seed) {
  const int m = ProbeCount(t), n = b.samples;
  const std::size_t o = static_cast<std::size_t>(r) * m;
  float* var_density = b.sigma + o;  // the probes' outputs, overwritten in place by the variances
  float* var_color = b.rgb_logvar + o;
  for (int j = 0; j < m; ++j) {
    var_density[j] = field::VarianceFromLogVar(b.sigma_logvar[o + j], t.variance_eps);
    var_color[j] = field::VarianceFromLogVar(b.rgb_logvar[o + j], t.variance_eps);
  }
  render::SampleScores(var_density, var_color, m, t.uncertainty_lambda, kScoreEps, b.probe_score + o);
  const bool prior = t.has_depth && HasDepthPrior(b.prior[r]);
  const int moved = prior ? t.stratified_samples : n;
  const base::CounterRng<float> uniform(step_seed, static_cast<std::uint64_t>(2 * r + 1));
  const float p = b.prior[r];
  render::PlaceSamples(
      b.camera_rays[r], t.rays.box, t.rays.times[b.picks[r].frame], n,
      [&](float lo, float hi, float* s, float* delta) {
        render::AdaptiveSamples(b.probe_s + o, b.probe_score + o, m, lo, hi, t.adaptive_floor, moved, uniform,
                                s, delta, static_cast<unsigned>(4 * n));
        if (!prior) return;
        render::GaussianSamplesAround(lo, hi, p, t.rays.guided.xi, t.rays.guided.gaussian_samples, uniform,
                                      static_cast<unsigned>(t.stratified_samples), s + moved);
        render::SortAscending(s, n);
        render::MidpointIntervals(s, n, lo, hi, delta);
      },
      b.Slot(r, n));
}

struct RayStepSums {
  double loss = 0, rgb_mse = 0;
};

// Ray r after the forward pass: composite, the ray's loss and rendered-colour error, and the gradients
// with respect to the samples' outputs (d_sigma, d_rgb, d_rgb_logvar; overwritten). With a learned
// background also the ray's direction, bg(d) and dL/d(bg) (ray_dir, background, d_background; for
// the background's backward pass once every ray is done).
ENDORECON_HD RayStepSums RayStepLoss(const StepTables& t, const StepBatch& b, int r) {
  const int n = b.samples;
  const std::size_t o = static_cast<std::size_t>(r) * n;
  float* w = b.weights + o;
  auto ray = render::CompositeRay(b.sigma + o, b.rgb + 3 * o, b.s + o, b.delta + o, n, w);
  const float* background = t.background;
  if (t.background_params) {
    scene::UnitDirection(b.camera_rays[r].direction, b.ray_dir + 3 * r);
    field::BackgroundSample(t.background_params, b.ray_dir + 3 * r, b.background + 3 * r);
    background = b.background + 3 * r;
  }
  render::AddBackground(ray, background);
  for (int j = 0; j < n; ++j) {
    b.d_rgb_logvar[o + j] = 0.0f;
    b.d_weights[o + j] = 0.0f;
    b.d_sigma[o + j] = 0.0f;
    for (int c = 0; c < 3; ++c) b.d_rgb[3 * (o + j) + c] = 0.0f;
  }
  render::RayCompositeGrad<float> grad;
  RayStepSums sums;
  sums.loss = RayLoss(ray, w, b.rgb + 3 * o, b.rgb_logvar + o, n, b.target + 3 * r, b.prior[r], t.terms,
                      &grad, b.d_rgb + 3 * o, b.d_rgb_logvar + o);
  sums.rgb_mse = RenderedColorL2(ray.rgb, b.target + 3 * r, 1.0f / 3.0f, static_cast<float*>(nullptr));
  if (t.background_params) {
    for (int c = 0; c < 3; ++c) b.d_background[3 * r + c] = grad.rgb[c] * ray.transmittance;
  }
  render::BackgroundBackward(background, grad);
  render::CompositeRayBackward(b.sigma + o, b.rgb + 3 * o, b.s + o, b.delta + o, w, ray, grad,
                               b.d_weights + o, b.d_sigma + o, b.d_rgb + 3 * o);
  return sums;
}

// Probe ray r of the uncertainty map after one dropout-on pass: its ray score of the aleatoric
// variances (sample_score.h RayScore).
ENDORECON_HD float ProbeRayScore(const StepTables& t, const StepBatch& b, int r) {
  const int n = b.samples;
  const std::size_t o = static_cast<std::size_t>(r) * n;
  render::CompositeRay(b.sigma + o, b.rgb + 3 * o, b.s + o, b.delta + o, n, b.weights + o);
  for (int j = 0; j < n; ++j) {
    b.sigma_logvar[o + j] = field::VarianceFromLogVar(b.sigma_logvar[o + j], t.variance_eps);
    b.rgb_logvar[o + j] = field::VarianceFromLogVar(b.rgb_logvar[o + j], t.variance_eps);
  }
  return render::RayScore(b.weights + o, b.sigma_logvar + o, b.rgb_logvar + o, n, t.uncertainty_lambda);
}

}  // namespace endorecon::train
