// The CPU step backend: the step's per-ray bodies (step_math.h) in TBB loops over host arrays, the
// host field's modules, train::Adam.
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "common/error.h"
#include "worker/engine/render/occupancy_grid.h"
#include "worker/engine/train/adam.h"
#include "worker/engine/train/step_backend.h"

namespace endorecon::train {
namespace {

// Batch-major arrays for one step, allocated once: rays x samples, nothing allocated per step.
struct HostBatch {
  std::vector<float> target, prior, s, delta, pos, dir, time;
  std::vector<float> sigma, sigma_logvar, rgb, rgb_logvar, weights;
  std::vector<float> d_weights, d_sigma, d_rgb, d_rgb_logvar;
  std::vector<float> ray_dir, background, d_background;
  std::vector<RayPick> picks;
  std::vector<render::CameraRay> camera_rays;
  std::vector<float> probe_s, probe_delta, probe_score;
  StepBatch view;

  HostBatch(int rays, int samples) {
    const std::size_t m = std::size_t(rays) * samples;
    target.resize(3 * std::size_t(rays));
    prior.resize(rays);
    picks.resize(rays);
    camera_rays.resize(rays);
    for (auto* v : {&s, &delta, &time, &sigma, &sigma_logvar, &rgb_logvar, &weights, &d_weights, &d_sigma,
                    &d_rgb_logvar, &probe_s, &probe_delta, &probe_score}) {
      v->resize(m);
    }
    for (auto* v : {&pos, &dir, &rgb, &d_rgb}) v->resize(3 * m);
    for (auto* v : {&ray_dir, &background, &d_background}) v->resize(3 * std::size_t(rays));
    view = {rays,
            samples,
            target.data(),
            prior.data(),
            s.data(),
            delta.data(),
            pos.data(),
            dir.data(),
            time.data(),
            sigma.data(),
            sigma_logvar.data(),
            rgb.data(),
            rgb_logvar.data(),
            weights.data(),
            d_weights.data(),
            d_sigma.data(),
            d_rgb.data(),
            d_rgb_logvar.data(),
            ray_dir.data(),
            background.data(),
            d_background.data(),
            picks.data(),
            camera_rays.data(),
            probe_s.data(),
            probe_delta.data(),
            probe_score.data()};
  }
};

// fn(r) for rays [0, rays) in parallel.
template <typename Fn>
void ForRays(int rays, Fn&& fn) {
  tbb::parallel_for(tbb::blocked_range<int>(0, rays, 64), [&](const tbb::blocked_range<int>& range) {
    for (int r = range.begin(); r != range.end(); ++r) fn(r);
  });
}

class CpuStep final : public StepBackend {
 public:
  CpuStep(field::Field& field, const TrainConfig& config, const StepTables& tables)
      : field_(field),
        tables_(tables),
        adam_(field.Blocks(), config.adam),
        batch_(tables.rays_per_batch, tables.samples) {}

  std::string device() const override { return "cpu"; }
  void TablesChanged() override {}

  StepResult Step(const StepRequest& request) override {
    const StepTables& t = tables_;
    const StepBatch& b = batch_.view;
    ForRays(b.rays, [&](int r) { PlaceStepRay(t, b, r, request.guided, request.step_seed); });
    if (request.guided > 0) Reallocate(request.guided, request.step_seed);
    const int n = b.rays * b.samples;
    const field::SampleBatch in{n, b.pos, b.time, b.dir};
    field::FieldOutput out{b.sigma, b.sigma_logvar, b.rgb, b.rgb_logvar};
    field_.Forward(in, out, /*dropout=*/true, request.dropout_seed);
    const RayStepSums sums = tbb::parallel_reduce(
        tbb::blocked_range<int>(0, b.rays, 64), RayStepSums{},
        [&](const tbb::blocked_range<int>& range, RayStepSums acc) {
          for (int r = range.begin(); r != range.end(); ++r) {
            const RayStepSums ray = RayStepLoss(t, b, r);
            acc.loss += ray.loss;
            acc.rgb_mse += ray.rgb_mse;
          }
          return acc;
        },
        [](RayStepSums a, const RayStepSums& c) {
          a.loss += c.loss;
          a.rgb_mse += c.rgb_mse;
          return a;
        });
    if (!std::isfinite(sums.loss)) {
      Fail(ErrorCode::kInternal, "training diverged: the loss is not finite at iteration " +
                                     std::to_string(request.iteration) + " (stage: loss)");
    }
    field_.ZeroGrad();
    field_.Backward(in, {b.d_sigma, nullptr, b.d_rgb, b.d_rgb_logvar});
    if (t.background_params) field_.BackgroundBackward(b.rays, b.ray_dir, b.background, b.d_background);
    const AdamStepReport report = adam_.Step(request.progress);
    if (!report.finite) {
      Fail(ErrorCode::kInternal,
           "training diverged: a gradient is not finite (or its square overflows float) at iteration " +
               std::to_string(request.iteration) + " (stage: backward, group " + report.bad_group + ")");
    }
    return {sums.loss, sums.rgb_mse / b.rays, n};
  }

  std::vector<float> ProbeScores(const std::vector<RayPick>& probes, std::uint64_t seed) override {
    const StepTables& t = tables_;
    const StepBatch& b = batch_.view;
    std::vector<float> scores(probes.size());
    for (std::size_t start = 0; start < probes.size(); start += std::size_t(b.rays)) {
      const int rays = int(std::min<std::size_t>(std::size_t(b.rays), probes.size() - start));
      ForRays(rays, [&](int r) {
        b.picks[r] = probes[start + r];
        PlaceTrainingRay(t.rays, b.picks[r], seed, r, b.samples, b.target + 3 * r, b.prior + r,
                         b.camera_rays + r, b.Slot(r, b.samples));
      });
      const field::SampleBatch in{rays * b.samples, b.pos, b.time, b.dir};
      field::FieldOutput out{b.sigma, b.sigma_logvar, b.rgb, b.rgb_logvar};
      field_.Infer(in, out, /*dropout=*/true, base::HashCombine(seed, start));
      ForRays(rays, [&](int r) { scores[start + r] = ProbeRayScore(t, b, r); });
    }
    return scores;
  }

  void Densities(const field::SampleBatch& batch, float* sigma) override { density_(batch, sigma); }

  void PullField() override {}
  void PushField() override {}
  void SaveOptimizer(std::ostream& out) const override { adam_.Save(out); }
  void LoadOptimizer(std::istream& in) override { adam_.Load(in); }

 private:
  // Guided rays [0, rays): probes, one dropout-on pass over them, then their samples re-placed.
  void Reallocate(int rays, std::uint64_t step_seed) {
    const StepTables& t = tables_;
    const StepBatch& b = batch_.view;
    ForRays(rays, [&](int r) { PlaceProbes(t, b, r, step_seed); });
    const field::SampleBatch in{rays * ProbeCount(t), b.pos, b.time, b.dir};
    field::FieldOutput out{b.sigma, b.sigma_logvar, b.rgb, b.rgb_logvar};
    field_.Infer(in, out, /*dropout=*/true, base::HashCombine(step_seed, 0xc0a25eull));
    ForRays(rays, [&](int r) { ReallocateRay(t, b, r, step_seed); });
  }

  field::Field& field_;
  const StepTables& tables_;
  Adam adam_;
  HostBatch batch_;
  render::DensityProbe density_ = render::HostDensity(field_);
};

}  // namespace

std::unique_ptr<StepBackend> MakeCpuStep(field::Field& field, const TrainConfig& config,
                                         const StepTables& tables) {
  return std::make_unique<CpuStep>(field, config, tables);
}

}  // namespace endorecon::train
