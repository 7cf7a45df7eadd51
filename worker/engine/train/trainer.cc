#include "worker/engine/train/trainer.h"

#include <spdlog/spdlog.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <cmath>
#include <istream>
#include <ostream>
#include <string>

#include "common/error.h"
#include "worker/engine/base/counter_rng.h"
#include "worker/engine/field/field_state.h"
#include "worker/engine/field/variance.h"
#include "worker/engine/render/adaptive_sampler.h"
#include "worker/engine/render/camera_ray.h"
#include "worker/engine/render/depth_guided_sampler.h"
#include "worker/engine/render/frame_renderer.h"
#include "worker/engine/render/sample_score.h"
#include "worker/engine/render/stratified_sampler.h"
#include "worker/engine/render/volume_renderer.h"
#include "worker/engine/train/losses.h"
#include "worker/engine/train/ray_loss.h"
#include "worker/engine/train/render_settings.h"
#include "worker/engine/train/run_clock.h"

namespace endorecon::train {
namespace {

// eps of the per-ray min-max normalisation of the variances (sample_score.h).
constexpr float kScoreEps = 1e-6f;

}  // namespace

// Batch-major arrays for one step, allocated once: rays x samples, nothing allocated per step.
struct Trainer::Batch {
  int rays = 0, samples = 0;
  std::vector<float> target, prior, s, delta, pos, dir, time;
  std::vector<float> sigma, sigma_logvar, rgb, rgb_logvar, weights;
  std::vector<float> d_weights, d_sigma, d_rgb, d_rgb_logvar;
  std::vector<RayPick> picks;
  std::vector<render::CameraRay> camera_rays;  // each ray and its span, as PlaceRay made it
  // The scoring pass of guided rays (ReallocateSamples): stratified probe depths, intervals and
  // scores. The probes' points and field outputs use the batch's own arrays, free until the guided
  // rays' samples are placed and the step's forward pass runs.
  std::vector<float> probe_s, probe_delta, probe_score;

  Batch(int r, int n) : rays(r), samples(n) {
    const std::size_t m = std::size_t(r) * n;
    target.resize(3 * std::size_t(r));
    prior.resize(r);
    picks.resize(r);
    for (auto* v : {&s, &delta, &time, &sigma, &sigma_logvar, &rgb_logvar, &weights, &d_weights, &d_sigma,
                    &d_rgb_logvar, &probe_s, &probe_delta, &probe_score}) {
      v->resize(m);
    }
    for (auto* v : {&pos, &dir, &rgb, &d_rgb}) v->resize(3 * m);
    camera_rays.resize(r);
  }
  render::RaySlot slot(int r, int n) {
    return render::RaySlotOf(s.data(), delta.data(), pos.data(), dir.data(), time.data(), r, n);
  }
};

Trainer::Trainer(const scene::Clip& clip, const TrainConfig& config, std::vector<int> train_frames,
                 std::uint64_t seed)
    : clip_(clip),
      config_(config),
      seed_(seed),
      box_(scene::FrustumBox(clip.cameras, clip.near, clip.far)),
      sampler_(clip, std::move(train_frames)),
      map_(sampler_, clip.width, clip.height, config.adaptive_map_stride),
      refiner_(clip, sampler_.frames()) {
  field_ = std::make_unique<field::Field>(config_.field, seed);
  adam_ = std::make_unique<Adam>(field_->Blocks(), config_.adam);
  // Without depth the same number of samples is spread stratified over [near, far].
  batch_ =
      std::make_unique<Batch>(config_.rays_per_batch, config_.depth_samples + config_.stratified_samples);
}

Trainer::~Trainer() = default;

void Trainer::PlaceRay(int r, const RayPick& pick, std::uint64_t step_seed) {
  Batch& b = *batch_;
  render::DepthGuidedConfig<float> guided;
  guided.xi = float(config_.depth_xi * (clip_.far - clip_.near));
  guided.gaussian_samples = config_.depth_samples;
  guided.stratified_samples = config_.stratified_samples;
  b.picks[r] = pick;
  const std::uint8_t* px = &clip_.rgb[pick.frame][3 * std::size_t(pick.pixel)];
  for (int c = 0; c < 3; ++c) b.target[3 * r + c] = px[c] / 255.0f;
  const float prior = clip_.has_depth() ? refiner_.Prior(pick.frame, pick.pixel) : 0.0f;
  b.prior[r] = prior;
  const base::CounterRng<float> uniform(step_seed, std::uint64_t(2 * r + 1));
  b.camera_rays[r] =
      render::CameraRayOf(clip_.cameras[pick.frame], pick.pixel, box_, &occupancy_, clip_.near, clip_.far);
  render::PlaceSamples(
      b.camera_rays[r], box_, clip_.times[pick.frame], b.samples,
      [&](float lo, float hi, float* s, float* delta) {
        if (clip_.has_depth()) {
          render::DepthGuidedSamples(lo, hi, prior, guided, uniform, s, delta);
        } else {
          render::StratifiedSamples(lo, hi, b.samples, uniform, s, delta);
        }
      },
      b.slot(r, b.samples));
}

void Trainer::SampleRays(int guided) {
  Batch& b = *batch_;
  const std::uint64_t step_seed = base::HashCombine(seed_, std::uint64_t(iteration_));
  tbb::parallel_for(tbb::blocked_range<int>(0, b.rays, 64), [&](const tbb::blocked_range<int>& range) {
    for (int r = range.begin(); r != range.end(); ++r) {
      const std::uint64_t stream = std::uint64_t(2 * r);
      const auto from_map = r < guided ? map_.Pick(step_seed ^ 0x6a1dedull, stream) : std::nullopt;
      PlaceRay(r, from_map ? *from_map : sampler_.Pick(step_seed, stream), step_seed);
    }
  });
  if (guided > 0) ReallocateSamples(guided, step_seed);
}

void Trainer::ReallocateSamples(int rays, std::uint64_t step_seed) {
  Batch& b = *batch_;
  const int n = b.samples;
  // Scored at stratified probes over the occupied span: the stratified part of the ray's samples (the
  // same draws) when the clip has depth, all n otherwise. With depth that is a third of the cost of
  // scoring every sample, and the probes cover the whole span, which is where points can be added.
  const int m = clip_.has_depth() ? config_.stratified_samples : n;
  const float eps = config_.variance_eps;
  const float xi = float(config_.depth_xi * (clip_.far - clip_.near));
  tbb::parallel_for(tbb::blocked_range<int>(0, rays, 64), [&](const tbb::blocked_range<int>& range) {
    for (int r = range.begin(); r != range.end(); ++r) {
      const base::CounterRng<float> uniform(step_seed, std::uint64_t(2 * r + 1));
      // Rows [0, rays * m) of pos/dir/time: guided rays' own, rewritten below once scored.
      render::PlaceSamples(
          b.camera_rays[r], box_, clip_.times[b.picks[r].frame], m,
          [&](float lo, float hi, float* s, float* delta) {
            render::StratifiedSamples(lo, hi, m, uniform, s, delta);
          },
          render::RaySlotOf(b.probe_s.data(), b.probe_delta.data(), b.pos.data(), b.dir.data(), b.time.data(),
                            r, m));
    }
  });
  const field::SampleBatch in{rays * m, b.pos.data(), b.time.data(), b.dir.data()};
  field::FieldOutput out{b.sigma.data(), b.sigma_logvar.data(), b.rgb.data(), b.rgb_logvar.data()};
  field_->Infer(in, out, /*dropout=*/true, base::HashCombine(step_seed, 0xc0a25eull));
  tbb::parallel_for(tbb::blocked_range<int>(0, rays, 64), [&](const tbb::blocked_range<int>& range) {
    for (int r = range.begin(); r != range.end(); ++r) {
      const std::size_t o = std::size_t(r) * m;
      float* var_density = &b.sigma[o];  // the probes' outputs, overwritten in place by the variances
      float* var_color = &b.rgb_logvar[o];
      for (int j = 0; j < m; ++j) {
        var_density[j] = field::VarianceFromLogVar(b.sigma_logvar[o + j], eps);
        var_color[j] = field::VarianceFromLogVar(b.rgb_logvar[o + j], eps);
      }
      render::SampleScores(var_density, var_color, m, config_.uncertainty_lambda, kScoreEps,
                           &b.probe_score[o]);
      // With a depth prior the Gaussian samples stay where PlaceRay put them (the same draws) and the
      // stratified ones move to where the scores are: the paper's additional points for uncertain
      // stretches, without taking any from the surface. Without a prior every sample moves.
      const bool prior = clip_.has_depth() && HasDepthPrior(b.prior[r]);
      const int moved = prior ? config_.stratified_samples : n;
      const base::CounterRng<float> uniform(step_seed, std::uint64_t(2 * r + 1));
      render::PlaceSamples(
          b.camera_rays[r], box_, clip_.times[b.picks[r].frame], n,
          [&](float lo, float hi, float* s, float* delta) {
            render::AdaptiveSamples(&b.probe_s[o], &b.probe_score[o], m, lo, hi, config_.adaptive_floor,
                                    moved, uniform, s, delta, unsigned(4 * n));
            if (!prior) return;
            render::GaussianSamplesAround(lo, hi, b.prior[r], xi, config_.depth_samples, uniform,
                                          unsigned(config_.stratified_samples), s + moved);
            render::SortAscending(s, n);
            render::MidpointIntervals(s, n, lo, hi, delta);
          },
          b.slot(r, n));
    }
  });
}

void Trainer::RefreshMap() {
  Batch& b = *batch_;
  const int n = b.samples;
  const std::uint64_t map_seed = base::HashCombine(seed_ ^ 0x3a9ull, std::uint64_t(iteration_));
  const float eps = config_.variance_eps;
  std::vector<float> scores(map_.cells(), 0.0f);
  std::vector<int> cells;
  for (int i = 0; i < map_.cells(); ++i) {
    if (map_.probe(i).pixel >= 0) cells.push_back(i);
  }
  for (std::size_t start = 0; start < cells.size(); start += std::size_t(b.rays)) {
    const int rays = int(std::min<std::size_t>(std::size_t(b.rays), cells.size() - start));
    tbb::parallel_for(tbb::blocked_range<int>(0, rays, 64), [&](const tbb::blocked_range<int>& range) {
      for (int r = range.begin(); r != range.end(); ++r) PlaceRay(r, map_.probe(cells[start + r]), map_seed);
    });
    const field::SampleBatch in{rays * n, b.pos.data(), b.time.data(), b.dir.data()};
    field::FieldOutput out{b.sigma.data(), b.sigma_logvar.data(), b.rgb.data(), b.rgb_logvar.data()};
    field_->Infer(in, out, /*dropout=*/true, base::HashCombine(map_seed, start));
    tbb::parallel_for(tbb::blocked_range<int>(0, rays, 64), [&](const tbb::blocked_range<int>& range) {
      for (int r = range.begin(); r != range.end(); ++r) {
        const std::size_t o = std::size_t(r) * n;
        render::CompositeRay(&b.sigma[o], &b.rgb[3 * o], &b.s[o], &b.delta[o], n, &b.weights[o]);
        for (int j = 0; j < n; ++j) {
          b.sigma_logvar[o + j] = field::VarianceFromLogVar(b.sigma_logvar[o + j], eps);
          b.rgb_logvar[o + j] = field::VarianceFromLogVar(b.rgb_logvar[o + j], eps);
        }
        scores[cells[start + r]] = render::RayScore(&b.weights[o], &b.sigma_logvar[o], &b.rgb_logvar[o], n,
                                                    config_.uncertainty_lambda);
      }
    });
  }
  map_.Set(std::move(scores), iteration_);
}

double Trainer::LossAndGradients(StepStats& stats) {
  Batch& b = *batch_;
  const float inv_rays = 1.0f / float(b.rays);
  RayLossTerms terms;
  terms.rgb_l2_scale = config_.rgb_l2_weight * inv_rays;
  if (clip_.has_depth()) terms.depth_scale = config_.depth_weight * inv_rays;
  terms.depth_range = float(clip_.far - clip_.near);
  terms.huber_delta = config_.depth_loss == "huber" ? config_.huber_delta : 0.0f;
  terms.nll_scale = config_.nll_weight * inv_rays;
  terms.nll_beta = config_.nll_beta;
  terms.variance_reg_scale = config_.variance_reg * inv_rays;
  terms.variance_eps = config_.variance_eps;
  struct Sums {
    double loss = 0, mse = 0;
  };
  const Sums sums = tbb::parallel_reduce(
      tbb::blocked_range<int>(0, b.rays, 64), Sums{},
      [&](const tbb::blocked_range<int>& range, Sums acc) {
        for (int r = range.begin(); r != range.end(); ++r) {
          const std::size_t o = std::size_t(r) * b.samples;
          float* w = &b.weights[o];
          const auto ray =
              render::CompositeRay(&b.sigma[o], &b.rgb[3 * o], &b.s[o], &b.delta[o], b.samples, w);
          float* d_lv = &b.d_rgb_logvar[o];
          std::fill(d_lv, d_lv + b.samples, 0.0f);
          float* d_rgb = &b.d_rgb[3 * o];
          std::fill(d_rgb, d_rgb + 3 * b.samples, 0.0f);
          render::RayCompositeGrad<float> grad;
          acc.loss += RayLoss(ray, w, &b.rgb[3 * o], &b.rgb_logvar[o], b.samples, &b.target[3 * r],
                              b.prior[r], terms, &grad, d_rgb, d_lv);
          acc.mse += RenderedColorL2(ray.rgb, &b.target[3 * r], 1.0f / 3.0f, static_cast<float*>(nullptr));
          float* d_w = &b.d_weights[o];
          std::fill(d_w, d_w + b.samples, 0.0f);
          float* d_sigma = &b.d_sigma[o];
          std::fill(d_sigma, d_sigma + b.samples, 0.0f);
          render::CompositeRayBackward(&b.sigma[o], &b.rgb[3 * o], &b.s[o], &b.delta[o], w, ray, grad, d_w,
                                       d_sigma, d_rgb);
        }
        return acc;
      },
      [](Sums a, const Sums& c) {
        a.loss += c.loss;
        a.mse += c.mse;
        return a;
      });
  stats.rgb_mse = sums.mse * inv_rays;
  stats.psnr = -10.0 * std::log10(std::max(stats.rgb_mse, 1e-12));
  return sums.loss;
}

DepthRefineStats Trainer::RefineDepth() {
  render::FrameRenderer renderer(*field_, box_, DepthRefineRenderSettings(config_, clip_.near, clip_.far));
  renderer.SetOccupancy(&occupancy_);
  const DepthRefineStats stats =
      refiner_.Refine(renderer, config_.depth_refine_fraction, config_.depth_refine_ema,
                      std::size_t(config_.depth_refine_pixels));
  spdlog::info(
      "depth refinement round {} at iteration {}: {} of {} measured priors moved, by {:.3g} on average",
      refiner_.rounds(), iteration_, stats.moved, stats.measured, stats.mean_shift);
  return stats;
}

render::OccupancyGrid BuildOccupancy(field::Field& field, const TrainConfig& config) {
  if (config.occupancy_resolution <= 0) return {};
  return render::OccupancyGrid::Build(field, render::OccupancyProbeTimes(config.field.deformation.enabled),
                                      config.occupancy_resolution, config.occupancy_min_alpha);
}

void Trainer::RebuildOccupancy() {
  occupancy_ = BuildOccupancy(*field_, config_);
  if (occupancy_.empty()) return;
  spdlog::info(
      "occupancy grid at iteration {}: {:.1f}% of the box occupied, {:.1f}% of the rays' range skipped",
      iteration_, 100.0 * occupancy_.occupied_fraction(), 100.0 * (1.0 - occupancy_span_fraction()));
}

double Trainer::occupancy_span_fraction() const {
  // Over a 16 x 16 lattice of pixels of the first training frame.
  const scene::Camera& camera = clip_.cameras[sampler_.frames().front()];
  double kept = 0;
  for (int i = 0; i < 16; ++i) {
    for (int j = 0; j < 16; ++j) {
      Eigen::Vector3d origin, direction;
      camera.Ray((2 * i + 1) * clip_.width / 32, (2 * j + 1) * clip_.height / 32, origin, direction);
      double lo = clip_.near, hi = clip_.far;
      occupancy_.Span(box_, origin, direction, clip_.near, clip_.far, &lo, &hi);
      kept += (hi - lo) / (clip_.far - clip_.near);
    }
  }
  return kept / 256.0;
}

StepStats Trainer::Step(double progress) {
  StepStats stats;
  if (progress < 0) progress = RunProgress(iteration_, config_.iterations, 0, 0);
  if (config_.occupancy_resolution > 0 && progress / config_.occupancy_every >= occupancy_builds_ + 1) {
    RebuildOccupancy();
    ++occupancy_builds_;
  }
  if (clip_.has_depth() && config_.depth_weight > 0 && config_.depth_refine_every > 0 &&
      progress / config_.depth_refine_every >= refiner_.rounds() + 1) {
    RefineDepth();
    stats.depth_refined = true;
  }
  if (config_.adaptive_sampling && config_.adaptive_ray_fraction > 0 && progress >= config_.adaptive_warmup) {
    if (map_.iteration() < 0 || iteration_ - map_.iteration() >= config_.adaptive_refresh) RefreshMap();
    if (map_.ready())
      stats.guided_rays = int(std::lround(config_.adaptive_ray_fraction * config_.rays_per_batch));
  }
  SampleRays(stats.guided_rays);
  Batch& b = *batch_;
  const int n = b.rays * b.samples;
  const field::SampleBatch in{n, b.pos.data(), b.time.data(), b.dir.data()};
  field::FieldOutput out{b.sigma.data(), b.sigma_logvar.data(), b.rgb.data(), b.rgb_logvar.data()};
  field_->Forward(in, out, /*dropout=*/true, base::HashCombine(seed_ ^ 0x5eed, std::uint64_t(iteration_)));
  stats.loss = LossAndGradients(stats);
  stats.samples = n;
  if (!std::isfinite(stats.loss)) {
    Fail(ErrorCode::kInternal, "training diverged: the loss is not finite at iteration " +
                                   std::to_string(iteration_) + " (stage: loss)");
  }
  field_->ZeroGrad();
  const field::FieldOutputGrad grad{b.d_sigma.data(), nullptr, b.d_rgb.data(), b.d_rgb_logvar.data()};
  field_->Backward(in, grad);
  const AdamStepReport report = adam_->Step(progress);
  if (!report.finite) {
    Fail(ErrorCode::kInternal,
         "training diverged: a gradient is not finite (or its square overflows float) at iteration " +
             std::to_string(iteration_) + " (stage: backward, group " + report.bad_group + ")");
  }
  ++iteration_;
  return stats;
}

void Trainer::Save(std::ostream& out) const {
  out.write(reinterpret_cast<const char*>(&iteration_), sizeof(iteration_));
  field::SaveFieldState(*field_, out);
  adam_->Save(out);
  map_.Save(out);
  refiner_.Save(out);
  out.write(reinterpret_cast<const char*>(&occupancy_builds_), sizeof(occupancy_builds_));
  occupancy_.Save(out);
}

void Trainer::Load(std::istream& in) {
  in.read(reinterpret_cast<char*>(&iteration_), sizeof(iteration_));
  if (!in) Fail(ErrorCode::kDataLoss, "checkpoint: truncated before the iteration count");
  field::LoadFieldState(*field_, in);
  adam_->Load(in);
  map_.Load(in);
  refiner_.Load(in);
  in.read(reinterpret_cast<char*>(&occupancy_builds_), sizeof(occupancy_builds_));
  if (!in) Fail(ErrorCode::kDataLoss, "checkpoint: truncated before the occupancy grid");
  occupancy_.Load(in);
}

}  // namespace endorecon::train
