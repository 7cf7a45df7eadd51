#include "worker/engine/train/trainer.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <istream>
#include <ostream>
#include <string>
#include <utility>

#include "common/error.h"
#include "worker/engine/base/counter_rng.h"
#include "worker/engine/base/psnr_from_mse.h"
#include "worker/engine/field/field_state.h"
#include "worker/engine/render/frame_renderer.h"
#include "worker/engine/train/background_start.h"
#include "worker/engine/train/render_settings.h"
#include "worker/engine/train/run_clock.h"

namespace endorecon::train {

Trainer::Trainer(const scene::Clip& clip, const TrainConfig& config, std::vector<int> train_frames,
                 std::uint64_t seed, const StepBackendFactory& backend, render::RenderBackendFactory render)
    : clip_(clip),
      config_(config),
      seed_(seed),
      box_(scene::ClipBox(clip)),
      sampler_(clip, std::move(train_frames)),
      map_(sampler_, clip.width, clip.height, config.adaptive_map_stride),
      refiner_(clip, sampler_.frames(), config.depth_fill_sigma),
      render_(std::move(render)) {
  for (int f = 0; f < clip.frame_count(); ++f) {
    rgb_frames_.push_back(clip.rgb[f].data());
    views_.push_back(clip.cameras[f].View());
  }
  // Without depth the same number of samples is spread stratified over [near, far].
  const int samples = config_.depth_samples + config_.stratified_samples;
  const float inv_rays = 1.0f / float(config_.rays_per_batch);
  StepTables& t = tables_;
  t.picks = sampler_.tables();
  t.rays.rgb = rgb_frames_.data();
  t.rays.views = views_.data();
  t.rays.times = clip.times.data();
  t.rays.box = box_.Frame();
  t.rays.near = clip.near;
  t.rays.far = clip.far;
  t.rays.guided.xi = float(config_.depth_xi * (clip.far - clip.near));
  t.rays.guided.gaussian_samples = config_.depth_samples;
  t.rays.guided.stratified_samples = config_.stratified_samples;
  t.terms.rgb_l2_scale = config_.rgb_l2_weight * inv_rays;
  if (clip.has_depth()) t.terms.depth_scale = config_.depth_weight * inv_rays;
  t.terms.depth_range = float(clip.far - clip.near);
  t.terms.huber_delta = config_.depth_loss == "huber" ? config_.huber_delta : 0.0f;
  t.terms.nll_scale = config_.nll_weight * inv_rays;
  t.terms.nll_beta = config_.nll_beta;
  t.terms.variance_reg_scale = config_.variance_reg * inv_rays;
  t.terms.variance_eps = config_.variance_eps;
  t.frames = clip.frame_count();
  t.rays_per_batch = config_.rays_per_batch;
  t.samples = samples;
  t.stratified_samples = config_.stratified_samples;
  t.has_depth = clip.has_depth();
  t.adaptive_floor = config_.adaptive_floor;
  t.uncertainty_lambda = config_.uncertainty_lambda;
  t.variance_eps = config_.variance_eps;
  BackgroundColor(config_, t.background);
  field_ = std::make_unique<field::Field>(config_.field, seed);
  if ((config_.background == "learned") != config_.field.learned_background) {
    FailInvalid("background '" + config_.background + "' with field.learned_background " +
                (config_.field.learned_background ? "on" : "off") + ": FitToScene sets the two together");
  }
  if (float* background = field::BlockValues(field_->Blocks(), "background")) {
    FitBackgroundToBorders(clip, sampler_.frames(), background);
    t.background_params = background;
  }
  if (!field_->deformation()) {
    deformation_start_.skipped = "no deformation (a static scene)";
  } else if (config_.deformation_start == "zero") {
    deformation_start_.skipped = "deformation_start is zero";
  } else {
    // Fitted by StartDeformation or the first Step; a trainer loaded from a checkpoint skips it.
    // Until then the deformation is zero, and a checkpoint written now says so.
    start_pending_ = true;
    deformation_start_.skipped = "not fitted yet: no step has run";
  }
  backend_ = backend(*field_, config_, tables_);
  UpdateTables();
  if (refiner_.filled() > 0) {
    spdlog::info(
        "depth priors: {} hole pixels filled from the depths measured around them (sigma {} px), {} left",
        refiner_.filled(), config_.depth_fill_sigma, refiner_.left());
  }
}

Trainer::~Trainer() = default;

void Trainer::StartDeformation() {
  if (!start_pending_) return;
  start_pending_ = false;
  deformation_start_ = FitDeformationToFlow(clip_, sampler_.frames(), box_, field_->deformation()->layout(),
                                            field::BlockValues(field_->Blocks(), "deform"));
  const FlowStart& s = deformation_start_;
  if (!s.skipped.empty()) {
    spdlog::info("deformation starts at zero: {}", s.skipped);
    return;
  }
  spdlog::info(
      "deformation started from optical flow: {} points on {} frames (mean flow {:.2f} px), "
      "{:.0f}% of their displacement fitted, {:.2f} s{}",
      s.points, s.frames, s.flow_px, 100 * s.fitted_fraction, s.seconds,
      s.assumed_depth > 0
          ? fmt::format("; the clip has no depth, its pixels lifted to {:.4g}", s.assumed_depth)
          : std::string());
  backend_->PushField();
}

void Trainer::UpdateTables() {
  if (clip_.has_depth()) {
    prior_frames_.resize(clip_.frame_count());
    for (int f = 0; f < clip_.frame_count(); ++f) prior_frames_[f] = refiner_.PriorFrame(f);
  }
  tables_.rays.priors = clip_.has_depth() ? prior_frames_.data() : nullptr;
  tables_.rays.occupancy = occupancy_.empty()
                               ? render::OccupancyView{}
                               : render::OccupancyView{occupancy_.cells(), occupancy_.resolution()};
  tables_.map = map_.tables();
  backend_->TablesChanged();
}

void Trainer::RefreshMap() {
  std::vector<RayPick> probes;
  std::vector<int> cells;
  for (int i = 0; i < map_.cells(); ++i) {
    if (map_.probe(i).pixel < 0) continue;
    cells.push_back(i);
    probes.push_back(map_.probe(i));
  }
  const std::uint64_t map_seed = base::HashCombine(seed_ ^ 0x3a9ull, std::uint64_t(iteration_));
  const std::vector<float> probe_scores = backend_->ProbeScores(probes, map_seed);
  std::vector<float> scores(map_.cells(), 0.0f);
  for (std::size_t i = 0; i < cells.size(); ++i) scores[cells[i]] = probe_scores[i];
  map_.Set(std::move(scores), iteration_);
  UpdateTables();
}

DepthRefineStats Trainer::RefineDepth() {
  backend_->PullField();
  render::FrameRenderer renderer(*field_, box_, DepthRefineRenderSettings(config_, clip_.near, clip_.far),
                                 render_);
  renderer.SetOccupancy(&occupancy_);
  const DepthRefineStats stats =
      refiner_.Refine(renderer, config_.depth_refine_fraction, config_.depth_refine_ema,
                      std::size_t(config_.depth_refine_pixels));
  UpdateTables();
  spdlog::info(
      "depth refinement round {} at iteration {}: {} of {} measured priors moved, by {:.3g} on average",
      refiner_.rounds(), iteration_, stats.moved, stats.measured, stats.mean_shift);
  return stats;
}

render::OccupancyGrid BuildOccupancy(const render::DensityProbe& density, const TrainConfig& config) {
  if (config.occupancy_resolution <= 0) return {};
  return render::OccupancyGrid::Build(density, render::OccupancyProbeTimes(config.field.deformation.enabled),
                                      config.occupancy_resolution, config.occupancy_min_alpha);
}

render::OccupancyGrid BuildOccupancy(field::Field& field, const TrainConfig& config) {
  return BuildOccupancy(render::HostDensity(field), config);
}

void Trainer::RebuildOccupancy() {
  // The densities come from where the parameters are (a GPU's copy: only points and densities move).
  occupancy_ = BuildOccupancy(
      [&](const field::SampleBatch& batch, float* sigma) { backend_->Densities(batch, sigma); }, config_);
  UpdateTables();
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
  StartDeformation();
  StepStats stats;
  if (progress < 0) progress = RunProgress(iteration_, config_.iterations, 0, 0);
  // A rebuild or a refinement round when the run's progress reaches its next time. Progress may leap
  // over several at once (a budget revised down, a slow step): one does for all of them, as the
  // next ones would see the same field (a 10 s run made three rounds and four rebuilds in nine
  // steps, 1.8 s of its 6.3 s of training; found 2026-12-06).
  if (config_.occupancy_resolution > 0 && progress / config_.occupancy_every >= occupancy_builds_ + 1) {
    RebuildOccupancy();
    occupancy_builds_ = std::max(occupancy_builds_ + 1, int(progress / config_.occupancy_every));
  }
  if (clip_.has_depth() && config_.depth_weight > 0 && config_.depth_refine_every > 0 &&
      progress / config_.depth_refine_every >= refiner_.rounds() + 1) {
    RefineDepth();
    refiner_.CatchUp(int(progress / config_.depth_refine_every));
    stats.depth_refined = true;
  }
  if (config_.adaptive_sampling && config_.adaptive_ray_fraction > 0 && progress >= config_.adaptive_warmup) {
    if (map_.iteration() < 0 || iteration_ - map_.iteration() >= config_.adaptive_refresh) RefreshMap();
    if (map_.ready())
      stats.guided_rays = int(std::lround(config_.adaptive_ray_fraction * config_.rays_per_batch));
  }
  StepRequest request;
  request.iteration = iteration_;
  request.step_seed = base::HashCombine(seed_, std::uint64_t(iteration_));
  request.dropout_seed = base::HashCombine(seed_ ^ 0x5eed, std::uint64_t(iteration_));
  request.guided = stats.guided_rays;
  request.progress = progress;
  const StepResult result = backend_->Step(request);
  stats.loss = result.loss;
  stats.rgb_mse = result.rgb_mse;
  stats.psnr = base::PsnrFromMse(result.rgb_mse);
  stats.samples = result.samples;
  ++iteration_;
  return stats;
}

void Trainer::Save(std::ostream& out) const {
  backend_->PullField();
  out.write(reinterpret_cast<const char*>(&iteration_), sizeof(iteration_));
  field::SaveFieldState(*field_, out);
  backend_->SaveOptimizer(out);
  map_.Save(out);
  refiner_.Save(out);
  out.write(reinterpret_cast<const char*>(&occupancy_builds_), sizeof(occupancy_builds_));
  occupancy_.Save(out);
}

int Trainer::ReadIteration(std::istream& in) {
  int iteration = 0;
  in.read(reinterpret_cast<char*>(&iteration), sizeof(iteration));
  if (!in) Fail(ErrorCode::kDataLoss, "checkpoint: truncated before the iteration count");
  return iteration;
}

void Trainer::Load(std::istream& in) {
  iteration_ = ReadIteration(in);
  if (start_pending_) {
    start_pending_ = false;
    deformation_start_.skipped = "resumed from a checkpoint, which holds the deformation";
  }
  field::LoadFieldState(*field_, in);
  backend_->PushField();
  backend_->LoadOptimizer(in);
  map_.Load(in);
  refiner_.Load(in);
  in.read(reinterpret_cast<char*>(&occupancy_builds_), sizeof(occupancy_builds_));
  if (!in) Fail(ErrorCode::kDataLoss, "checkpoint: truncated before the occupancy grid");
  occupancy_.Load(in);
  UpdateTables();
}

}  // namespace endorecon::train
