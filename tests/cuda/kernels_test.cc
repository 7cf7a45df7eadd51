// Each CUDA kernel against the CPU code on random inputs: the kernels call the same ENDORECON_HD
// functions, so the results agree up to float rounding (the device fuses multiply-adds, its
// transcendentals round differently, and atomics sum in any order). Skipped without a GPU.
#include "worker/engine/cuda/kernels.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include "worker/engine/base/counter_rng.h"
#include "worker/engine/cuda/device.h"
#include "worker/engine/field/hash_grid.h"
#include "worker/engine/render/depth_guided_sampler.h"
#include "worker/engine/render/stratified_sampler.h"
#include "worker/engine/render/volume_renderer.h"
#include "worker/engine/train/ray_loss.h"

namespace endorecon::cuda {
namespace {

using Composite = render::RayComposite<float>;
using CompositeGrad = render::RayCompositeGrad<float>;

// |a - b| <= tol * max(1, |b|), element by element, naming the first few that differ.
void ExpectClose(const std::vector<float>& gpu, const std::vector<float>& cpu, float tol, const char* what) {
  ASSERT_EQ(gpu.size(), cpu.size()) << what;
  int bad = 0;
  for (std::size_t i = 0; i < cpu.size() && bad < 5; ++i) {
    const float bound = tol * std::fmax(1.0f, std::fabs(cpu[i]));
    if (!(std::fabs(gpu[i] - cpu[i]) <= bound)) {
      ADD_FAILURE() << what << "[" << i << "]: gpu " << gpu[i] << ", cpu " << cpu[i];
      ++bad;
    }
  }
}

class CudaKernelsTest : public ::testing::Test {
 protected:
  void SetUp() override {
    if (DeviceCount() == 0) GTEST_SKIP() << "no CUDA device: " << ListDevices().problem;
    SetDevice(0);
  }

  std::vector<float> Uniform(std::size_t n, float lo, float hi) {
    std::uniform_real_distribution<float> u(lo, hi);
    std::vector<float> v(n);
    for (float& x : v) x = u(rng_);
    return v;
  }

  struct RayBatch {
    std::vector<float> sigma, rgb, s, delta;
  };

  // Densities partly negative (they count as 0), colours in [0, 1], stratified samples in [1, 3].
  RayBatch RandomRays(int rays, int samples) {
    const std::size_t n = std::size_t(rays) * samples;
    RayBatch b{Uniform(n, -0.5f, 6.0f), Uniform(3 * n, 0.0f, 1.0f), std::vector<float>(n),
               std::vector<float>(n)};
    for (int r = 0; r < rays; ++r) {
      const std::size_t o = std::size_t(r) * samples;
      render::StratifiedSamples(1.0f, 3.0f, samples, base::CounterRng<float>(7, r), &b.s[o], &b.delta[o]);
    }
    return b;
  }

  // The GPU's table and position gradients against the CPU grid's per-level scatter, for positions in
  // `pos` (n x 3).
  void ExpectGridBackwardMatchesTheCpu(const field::HashGrid<float>& grid, const std::vector<float>& pos,
                                       bool position) {
    const int n = static_cast<int>(pos.size() / 3), dim = grid.output_dim(), features = grid.features();
    const std::vector<float> params = Uniform(grid.param_count(), -1.0f, 1.0f);
    const std::vector<float> dfeat = Uniform(std::size_t(n) * dim, -1.0f, 1.0f);
    const std::vector<float> scale = Uniform(n, 0.5f, 2.0f);
    std::vector<float> grads(grid.param_count(), 0.0f), dpos(3 * std::size_t(n), 0.0f);
    for (int l = 0; l < grid.levels(); ++l) {
      grid.BackwardLevel(l, pos.data(), n, dfeat.data() + l * features, dim, scale.data(), grads.data(),
                         position ? params.data() : nullptr, position ? dpos.data() : nullptr);
    }
    DeviceArray<float> d_params(params), d_pos(pos), d_dfeat(dfeat), d_scale(scale), d_grads(grads.size()),
        d_dpos(dpos.size());
    d_grads.Zero();
    d_dpos.Zero();
    HashGridBackward(grid, d_pos.data(), n, d_dfeat.data(), dim, d_scale.data(), 1, d_grads.data(),
                     position ? d_params.data() : nullptr, position ? d_dpos.data() : nullptr);
    Synchronize();
    // Sums of many atomics: rounding grows with the number of samples per slot.
    ExpectClose(d_grads.Download(), grads, 1e-4f, "table gradient");
    if (position) ExpectClose(d_dpos.Download(), dpos, 1e-4f, "position gradient");
  }

  std::mt19937 rng_{20240611};
};

// Grids with dense and hashed levels, positions partly outside [0, 1]^3 (clamped).
field::HashGridConfig GridConfig(int features) {
  field::HashGridConfig c;
  c.levels = 4;
  c.features = features;
  c.log2_table = 10;
  c.base_resolution = 4;
  c.scale = 2.0;
  return c;
}

TEST_F(CudaKernelsTest, HashGridForwardMatchesTheCpuGrid) {
  for (int features : {1, 2, 4, 8}) {
    const field::HashGrid<float> grid(GridConfig(features));
    ASSERT_TRUE(grid.level(0).dense && !grid.level(grid.levels() - 1).dense);
    const int n = 5000, dim = grid.output_dim();
    const std::vector<float> params = Uniform(grid.param_count(), -1.0f, 1.0f);
    const std::vector<float> pos = Uniform(3 * std::size_t(n), -0.1f, 1.1f);
    std::vector<float> cpu(std::size_t(n) * dim);
    grid.ForwardRows(params.data(), pos.data(), n, cpu.data(), dim);

    DeviceArray<float> d_params(params), d_pos(pos), d_feat(cpu.size());
    HashGridForward(grid, d_params.data(), d_pos.data(), n, d_feat.data(), dim);
    Synchronize();
    ExpectClose(d_feat.Download(), cpu, 1e-5f, "features");
  }
}

TEST_F(CudaKernelsTest, HashGridBackwardMatchesTheCpuGrid) {
  for (int features : {2, 8}) {
    for (bool position : {false, true}) {
      const field::HashGrid<float> grid(GridConfig(features));
      ExpectGridBackwardMatchesTheCpu(grid, Uniform(3 * std::size_t(5000), -0.1f, 1.1f), position);
    }
  }
}

// Samples along rays, as the trainer's: neighbouring threads fall in the same cells, in runs that
// start and end anywhere in a warp (rays of 37 samples, a batch that ends inside a warp), which the
// warp's sums before the atomics must add up exactly as the CPU's serial scatter.
TEST_F(CudaKernelsTest, HashGridBackwardSumsSamplesThatShareCells) {
  const int rays = 150, samples = 37;
  const std::vector<float> ends = Uniform(6 * std::size_t(rays), 0.0f, 1.0f);
  std::vector<float> pos;
  for (int r = 0; r < rays; ++r) {
    for (int j = 0; j < samples; ++j) {
      const float t = 0.2f * static_cast<float>(j) / samples;  // a short segment: long runs per cell
      for (int a = 0; a < 3; ++a)
        pos.push_back(ends[6 * r + a] + t * (ends[6 * r + 3 + a] - ends[6 * r + a]));
    }
  }
  for (int features : {1, 2, 4}) {
    for (bool position : {false, true}) {
      const field::HashGrid<float> grid(GridConfig(features));
      ExpectGridBackwardMatchesTheCpu(grid, pos, position);
    }
  }
}

TEST_F(CudaKernelsTest, SamplersMatchTheCpuSamplers) {
  const int rays = 300;
  const float near = 0.5f, far = 4.0f;
  const RayStreams streams{0x1234abcdull, 1, 2};
  render::DepthGuidedConfig<float> config;
  config.xi = 0.3f;
  config.gaussian_samples = 24;
  config.stratified_samples = 8;
  const int samples = config.gaussian_samples + config.stratified_samples;
  std::vector<float> prior = Uniform(rays, near, far);
  prior[0] = 0.0f;        // no prior: all stratified
  prior[1] = near - 1;    // unknown as well
  prior[2] = far + 0.5f;  // beyond far: clamped samples

  std::vector<float> s(std::size_t(rays) * samples), delta(s.size()), s_guided(s.size()),
      delta_guided(s.size());
  for (int r = 0; r < rays; ++r) {
    const base::CounterRng<float> rng(streams.seed, streams.stream_base + streams.stream_step * r);
    const std::size_t o = std::size_t(r) * samples;
    render::StratifiedSamples(near, far, samples, rng, &s[o], &delta[o]);
    render::DepthGuidedSamples(near, far, prior[r], config, rng, &s_guided[o], &delta_guided[o]);
  }

  DeviceArray<float> d_prior(prior), d_s(s.size()), d_delta(s.size());
  StratifiedSampleRays(near, far, rays, samples, streams, d_s.data(), d_delta.data());
  Synchronize();
  ExpectClose(d_s.Download(), s, 1e-5f, "stratified s");
  ExpectClose(d_delta.Download(), delta, 1e-5f, "stratified delta");

  DepthGuidedSampleRays(near, far, d_prior.data(), rays, config, streams, d_s.data(), d_delta.data());
  Synchronize();
  ExpectClose(d_s.Download(), s_guided, 1e-4f, "depth-guided s");
  ExpectClose(d_delta.Download(), delta_guided, 1e-4f, "depth-guided delta");
}

std::vector<float> Slice(const std::vector<float>& v, std::size_t begin, std::size_t count) {
  return std::vector<float>(v.begin() + begin, v.begin() + begin + count);
}

// The Composite fields as a flat list, for comparison.
std::vector<float> Flatten(const std::vector<Composite>& rays) {
  std::vector<float> v;
  for (const Composite& c : rays) {
    v.insert(v.end(),
             {c.rgb[0], c.rgb[1], c.rgb[2], c.depth, c.opacity, c.transmittance, float(c.samples_used)});
  }
  return v;
}

TEST_F(CudaKernelsTest, CompositeForwardAndBackwardMatchTheCpu) {
  const int rays = 400, samples = 48;
  // Most rays stop early (their optical depth over [1, 3] is about 5.5 +- 0.5), a few do not.
  const float min_transmittance = 1e-2f;
  const RayBatch b = RandomRays(rays, samples);
  const std::size_t n = b.sigma.size();
  std::vector<CompositeGrad> grad(rays);
  const std::vector<float> g = Uniform(5 * std::size_t(rays), -1.0f, 1.0f);
  for (int r = 0; r < rays; ++r) {
    grad[r].rgb[0] = g[5 * r];
    grad[r].rgb[1] = g[5 * r + 1];
    grad[r].rgb[2] = g[5 * r + 2];
    grad[r].depth = g[5 * r + 3];
    grad[r].opacity = g[5 * r + 4];
  }
  const std::vector<float> d_weights = Uniform(n, -1.0f, 1.0f);

  std::vector<float> weights(n), d_sigma(n, 0.0f), d_rgb(3 * n, 0.0f);
  std::vector<Composite> out(rays);
  for (int r = 0; r < rays; ++r) {
    const std::size_t o = std::size_t(r) * samples;
    out[r] = render::CompositeRay(&b.sigma[o], &b.rgb[3 * o], &b.s[o], &b.delta[o], samples, &weights[o],
                                  min_transmittance);
    render::CompositeRayBackward(&b.sigma[o], &b.rgb[3 * o], &b.s[o], &b.delta[o], &weights[o], out[r],
                                 grad[r], &d_weights[o], &d_sigma[o], &d_rgb[3 * o]);
  }
  int stopped = 0;
  for (const Composite& c : out) stopped += c.samples_used < samples;
  std::printf("gpu-check: composite: %d of %d rays stopped early\n", stopped, rays);
  ASSERT_GT(stopped, 0) << "no ray terminated early; the test would not cover it";
  ASSERT_LT(stopped, rays) << "every ray terminated early; the test would not cover the others";

  DeviceArray<float> dev_sigma(b.sigma), dev_rgb(b.rgb), dev_s(b.s), dev_delta(b.delta), dev_weights(n),
      dev_d_weights(d_weights), dev_d_sigma(n), dev_d_rgb(3 * n);
  DeviceArray<Composite> dev_out(rays);
  DeviceArray<CompositeGrad> dev_grad(grad);
  CompositeRays(dev_sigma.data(), dev_rgb.data(), dev_s.data(), dev_delta.data(), rays, samples,
                min_transmittance, dev_weights.data(), dev_out.data());
  dev_d_sigma.Zero();
  dev_d_rgb.Zero();
  CompositeRaysBackward(dev_sigma.data(), dev_rgb.data(), dev_s.data(), dev_delta.data(), dev_weights.data(),
                        rays, samples, dev_out.data(), dev_grad.data(), dev_d_weights.data(),
                        dev_d_sigma.data(), dev_d_rgb.data());
  Synchronize();
  const std::vector<Composite> gpu_out = dev_out.Download();
  const std::vector<float> gpu_weights = dev_weights.Download(), gpu_d_sigma = dev_d_sigma.Download(),
                           gpu_d_rgb = dev_d_rgb.Download();
  // Where T crosses the threshold within rounding, the GPU may stop one sample earlier or later than
  // the CPU; such rays (expected: very few) are counted, not compared.
  int differ = 0;
  for (int r = 0; r < rays; ++r) {
    if (gpu_out[r].samples_used != out[r].samples_used) {
      EXPECT_LE(std::abs(gpu_out[r].samples_used - out[r].samples_used), 1) << "ray " << r;
      ++differ;
      continue;
    }
    const std::size_t o = std::size_t(r) * samples;
    ExpectClose(Flatten({gpu_out[r]}), Flatten({out[r]}), 1e-4f, "composite");
    ExpectClose(Slice(gpu_weights, o, samples), Slice(weights, o, samples), 1e-4f, "weights");
    ExpectClose(Slice(gpu_d_sigma, o, samples), Slice(d_sigma, o, samples), 1e-4f, "d_sigma");
    ExpectClose(Slice(gpu_d_rgb, 3 * o, 3 * samples), Slice(d_rgb, 3 * o, 3 * samples), 1e-4f, "d_rgb");
  }
  EXPECT_LE(differ, rays / 50);
}

TEST_F(CudaKernelsTest, RayLossesMatchTheCpuLosses) {
  const int rays = 300, samples = 32;
  const std::size_t n = std::size_t(rays) * samples;
  const RayBatch b = RandomRays(rays, samples);
  std::vector<float> weights(n);
  std::vector<Composite> composite(rays);
  for (int r = 0; r < rays; ++r) {
    const std::size_t o = std::size_t(r) * samples;
    composite[r] =
        render::CompositeRay(&b.sigma[o], &b.rgb[3 * o], &b.s[o], &b.delta[o], samples, &weights[o]);
  }
  const std::vector<float> log_var = Uniform(n, -6.0f, 3.0f);
  const std::vector<float> target = Uniform(3 * std::size_t(rays), 0.0f, 1.0f);
  std::vector<float> prior = Uniform(rays, 1.0f, 3.0f);
  prior[0] = 0.0f;  // unknown: no depth term

  for (float huber_delta : {0.0f, 0.05f}) {
    train::RayLossTerms terms;
    terms.rgb_l2_scale = 0.7f;
    terms.depth_scale = 0.2f;
    terms.depth_range = 2.0f;
    terms.huber_delta = huber_delta;
    terms.nll_scale = 0.3f;
    terms.variance_reg_scale = 0.01f;
    terms.variance_eps = 1e-3f;

    std::vector<float> loss(rays), grad_flat, d_mean(3 * n, 0.0f), d_lv(n, 0.0f);
    for (int r = 0; r < rays; ++r) {
      const std::size_t o = std::size_t(r) * samples;
      CompositeGrad g;
      loss[r] = train::RayLoss(composite[r], &weights[o], &b.rgb[3 * o], &log_var[o], samples,
                               &target[3 * std::size_t(r)], prior[r], terms, &g, &d_mean[3 * o], &d_lv[o]);
      grad_flat.insert(grad_flat.end(), {g.rgb[0], g.rgb[1], g.rgb[2], g.depth, g.opacity});
    }

    DeviceArray<Composite> dev_rays(composite);
    DeviceArray<float> dev_weights(weights), dev_mean(b.rgb), dev_lv(log_var), dev_target(target),
        dev_prior(prior), dev_loss(rays), dev_d_mean(3 * n), dev_d_lv(n);
    DeviceArray<CompositeGrad> dev_grad(rays);
    dev_d_mean.Zero();
    dev_d_lv.Zero();
    RayLosses(dev_rays.data(), dev_weights.data(), dev_mean.data(), dev_lv.data(), dev_target.data(),
              dev_prior.data(), rays, samples, terms, dev_loss.data(), dev_grad.data(), dev_d_mean.data(),
              dev_d_lv.data());
    Synchronize();
    ExpectClose(dev_loss.Download(), loss, 1e-4f, "loss");
    std::vector<float> gpu_grad;
    for (const CompositeGrad& g : dev_grad.Download())
      gpu_grad.insert(gpu_grad.end(), {g.rgb[0], g.rgb[1], g.rgb[2], g.depth, g.opacity});
    ExpectClose(gpu_grad, grad_flat, 1e-4f, "ray gradient");
    ExpectClose(dev_d_mean.Download(), d_mean, 1e-4f, "d_mean_rgb");
    ExpectClose(dev_d_lv.Download(), d_lv, 1e-4f, "d_log_var");
  }
}

}  // namespace
}  // namespace endorecon::cuda
