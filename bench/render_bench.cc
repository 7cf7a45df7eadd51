// Throughput of the per-ray rendering math on the CPU, float32, 64 samples per ray:
//   sampling    stratified samples from the counter-based RNG
//   composite   volume rendering forward + backward
//   ray step    composite + RGB NLL + rendered-colour L2 + depth Huber + variance regulariser,
//               forward and backward (everything per ray except the field)
// on one thread and on all threads (TBB over tiles of rays). Usage: render_bench [seconds per case]
#include <tbb/info.h>
#include <tbb/parallel_for.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <random>
#include <vector>

#include "worker/engine/base/counter_rng.h"
#include "worker/engine/render/stratified_sampler.h"
#include "worker/engine/render/volume_renderer.h"
#include "worker/engine/train/losses.h"

namespace {

using namespace endorecon;

constexpr int kSamples = 64;
constexpr int kRays = 8192;  // one batch; inputs stay in L2/L3 like a tile of a training step
constexpr int kTile = 256;

struct Batch {
  std::vector<float> sigma, rgb, log_var, s, delta, weights, d_weights, d_sigma, d_rgb, d_log_var, target,
      prior;
};

Batch MakeBatch() {
  Batch b;
  const int n = kRays * kSamples;
  b.sigma.resize(n);
  b.rgb.resize(3 * n);
  b.log_var.resize(n);
  b.s.resize(n);
  b.delta.resize(n);
  b.weights.resize(n);
  b.d_weights.resize(n);
  b.d_sigma.resize(n);
  b.d_rgb.resize(3 * n);
  b.d_log_var.resize(n);
  b.target.resize(3 * kRays);
  b.prior.resize(kRays);
  std::mt19937 gen(1);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  for (int r = 0; r < kRays; ++r) {
    render::StratifiedSamples(2.0f, 6.0f, kSamples, base::CounterRng<float>(1, r), &b.s[r * kSamples],
                              &b.delta[r * kSamples]);
    b.prior[r] = 2.0f + 4.0f * u(gen);
    for (int c = 0; c < 3; ++c) b.target[3 * r + c] = u(gen);
  }
  for (int i = 0; i < n; ++i) {
    b.sigma[i] = 20.0f * u(gen) * u(gen);
    b.log_var[i] = 4.0f * u(gen) - 3.0f;
  }
  for (float& c : b.rgb) c = u(gen);
  return b;
}

void Sample(Batch& b, int r) {
  render::StratifiedSamples(2.0f, 6.0f, kSamples, base::CounterRng<float>(7, r), &b.s[r * kSamples],
                            &b.delta[r * kSamples]);
}

render::RayComposite<float> Composite(Batch& b, int r) {
  const int o = r * kSamples;
  return render::CompositeRay(&b.sigma[o], &b.rgb[3 * o], &b.s[o], &b.delta[o], kSamples, &b.weights[o]);
}

void CompositeBackward(Batch& b, int r, const render::RayComposite<float>& out,
                       const render::RayCompositeGrad<float>& grad, const float* d_weights) {
  const int o = r * kSamples;
  render::CompositeRayBackward(&b.sigma[o], &b.rgb[3 * o], &b.s[o], &b.delta[o], &b.weights[o], out, grad,
                               d_weights, &b.d_sigma[o], &b.d_rgb[3 * o]);
}

void CompositeOnly(Batch& b, int r) {
  const render::RayComposite<float> out = Composite(b, r);
  const render::RayCompositeGrad<float> grad{{0.1f, 0.2f, 0.3f}, 0.05f, 0.0f};
  CompositeBackward(b, r, out, grad, nullptr);
}

void RayStep(Batch& b, int r) {
  const int o = r * kSamples;
  const render::RayComposite<float> out = Composite(b, r);
  float* d_w = &b.d_weights[o];
  for (int j = 0; j < kSamples; ++j) d_w[j] = 0.0f;
  render::RayCompositeGrad<float> grad;
  const float* target = &b.target[3 * r];
  train::RgbNll(&b.weights[o], &b.rgb[3 * o], &b.log_var[o], kSamples, target, 1e-3f, 1.0f, d_w,
                &b.d_rgb[3 * o], &b.d_log_var[o]);
  train::RenderedColorL2(out.rgb, target, 1.0f, grad.rgb);
  train::DepthHuber(out.depth, b.prior[r], 0.1f, 0.1f, &grad.depth);
  train::VarianceRegularizer(&b.log_var[o], kSamples, 1e-3f, 0.01f, &b.d_log_var[o]);
  CompositeBackward(b, r, out, grad, d_w);
}

// Runs `per_ray` over the batch until `seconds` have passed; returns rays per second.
double Measure(Batch& b, const std::function<void(Batch&, int)>& per_ray, double seconds, bool parallel) {
  using Clock = std::chrono::steady_clock;
  const auto start = Clock::now();
  long long rays = 0;
  double elapsed = 0;
  while (elapsed < seconds) {
    if (parallel) {
      tbb::parallel_for(0, kRays / kTile, [&](int tile) {
        for (int r = tile * kTile; r < (tile + 1) * kTile; ++r) per_ray(b, r);
      });
    } else {
      for (int r = 0; r < kRays; ++r) per_ray(b, r);
    }
    rays += kRays;
    elapsed = std::chrono::duration<double>(Clock::now() - start).count();
  }
  return static_cast<double>(rays) / elapsed;
}

}  // namespace

int main(int argc, char** argv) {
  double seconds = 1.0;
  CLI::App app{"render_bench: compositing and sampling, rays per second"};
  app.add_option("seconds", seconds, "seconds per case")->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  Batch batch = MakeBatch();
  const int threads = tbb::info::default_concurrency();
  std::printf("render_bench: float32, %d samples/ray, batch of %d rays, %.1f s per case, %d threads\n",
              kSamples, kRays, seconds, threads);
  std::printf("%-34s %8s %14s %16s\n", "case", "threads", "rays/s", "samples/s");
  const struct {
    const char* name;
    void (*fn)(Batch&, int);
  } cases[] = {{"sampling (stratified)", Sample},
               {"composite forward+backward", CompositeOnly},
               {"ray step (composite+losses, f+b)", RayStep}};
  for (const auto& c : cases) {
    for (bool parallel : {false, true}) {
      const double rays_per_s = Measure(batch, c.fn, seconds, parallel);
      std::printf("%-34s %8d %14.3e %16.3e\n", c.name, parallel ? threads : 1, rays_per_s,
                  rays_per_s * kSamples);
    }
  }
  return 0;
}
