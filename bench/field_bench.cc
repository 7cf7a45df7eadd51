// Throughput of the neural field on the CPU, float32, batches of 32768 samples (512 rays x 64 samples,
// rays crossing the unit box, one time per ray):
//   forward+backward   Field::Forward (dropout on) + Field::Backward, the field's part of a training step
//   forward            Field::Forward alone (keeps activations)
//   infer              Field::Infer (rendering: nothing kept)
//   zero grad          Field::ZeroGrad (a training step does it once)
//   heads only         both heads' MLPs, forward + backward over the same batch (their own loops), as
//                      GFLOP/s (2 flops per multiply-add, backward counted as 2x forward) against the
//                      fp32 FMA peak measured at start-up on the same threads (12 independent chains
//                      of 512-bit FMAs per thread, 256-bit without AVX-512; the design brief's ~190 GFLOP/s
//                      came from a kernel bound by store forwarding: this machine kind reaches ~550 on 2
//                      cores)
// for the CPU preset (with and without deformation) and the paper preset. Each line gives wall-clock
// throughput and samples per CPU-second: on a machine shared with other work the second is the steadier.
// Usage: field_bench [--threads N] [--seconds S] [--preset cpu|paper|both]
#include <fmt/format.h>
#include <tbb/global_control.h>
#include <tbb/info.h>
#include <tbb/parallel_for.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include "worker/engine/field/field.h"
#include "worker/engine/field/field_description.h"

#if defined(__AVX512F__) || (defined(__AVX2__) && defined(__FMA__))
#include <immintrin.h>
#endif

namespace {

using namespace endorecon;
using Clock = std::chrono::steady_clock;

constexpr int kRays = 512;
constexpr int kSamplesPerRay = 64;
constexpr int kBatch = kRays * kSamplesPerRay;

struct Batch {
  std::vector<float> pos, time, dir, sigma, sigma_lv, rgb, rgb_lv, d_sigma, d_sigma_lv, d_rgb, d_rgb_lv;
};

// Rays from points below the box towards random points above it, sampled evenly inside it: neighbouring
// samples are close in space, as in training.
Batch MakeBatch() {
  Batch b;
  std::mt19937 gen(7);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  for (int r = 0; r < kRays; ++r) {
    const float o[3] = {u(gen), u(gen), 0.0f}, e[3] = {u(gen), u(gen), 1.0f};
    float d[3] = {e[0] - o[0], e[1] - o[1], 1.0f};
    const float len = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    const float t = u(gen);
    for (int s = 0; s < kSamplesPerRay; ++s) {
      const float z = (s + u(gen)) / kSamplesPerRay;
      for (int a = 0; a < 3; ++a) {
        b.pos.push_back(o[a] + z * (e[a] - o[a]));
        b.dir.push_back(d[a] / len);
      }
      b.time.push_back(t);
    }
  }
  b.sigma.resize(kBatch);
  b.sigma_lv.resize(kBatch);
  b.rgb.resize(3 * kBatch);
  b.rgb_lv.resize(kBatch);
  for (int i = 0; i < kBatch; ++i) {
    b.d_sigma.push_back(u(gen) - 0.5f);
    b.d_sigma_lv.push_back(u(gen) - 0.5f);
    b.d_rgb_lv.push_back(u(gen) - 0.5f);
    for (int c = 0; c < 3; ++c) b.d_rgb.push_back(u(gen) - 0.5f);
  }
  return b;
}

// Seconds per call of fn (wall clock, and CPU time of the whole process: other processes sharing the
// cores inflate the first but hardly the second), over at least `seconds` of calls after one warm-up.
struct Timing {
  double wall = 0, cpu = 0;
};

double CpuSeconds() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

Timing TimePerCall(double seconds, const std::function<void()>& fn) {
  fn();
  int calls = 0;
  const auto start = Clock::now();
  const double cpu_start = CpuSeconds();
  double elapsed = 0;
  do {
    fn();
    ++calls;
    elapsed = std::chrono::duration<double>(Clock::now() - start).count();
  } while (elapsed < seconds);
  return {elapsed / calls, (CpuSeconds() - cpu_start) / calls};
}

// fp32 FMA peak of `threads` threads in GFLOP/s: each runs 12 independent chains of FMAs of the widest
// vectors the build has (512-bit, else 256-bit: enough chains to cover the latency of two FMA pipes). 0
// when the build has neither AVX-512 nor AVX2 with FMA.
#if defined(__AVX512F__)
using Lanes = __m512;
inline Lanes Splat(float x) { return _mm512_set1_ps(x); }
inline Lanes Fma(Lanes a, Lanes m, Lanes c) { return _mm512_fmadd_ps(a, m, c); }
inline float First(Lanes a) { return _mm512_cvtss_f32(a); }
#elif defined(__AVX2__) && defined(__FMA__)
using Lanes = __m256;
inline Lanes Splat(float x) { return _mm256_set1_ps(x); }
inline Lanes Fma(Lanes a, Lanes m, Lanes c) { return _mm256_fmadd_ps(a, m, c); }
inline float First(Lanes a) { return _mm256_cvtss_f32(a); }
#endif

double PeakGflops(int threads) {
#if defined(__AVX512F__) || (defined(__AVX2__) && defined(__FMA__))
  constexpr long kIters = 20'000'000;
  constexpr int kChains = 12;
  constexpr double kFlopsPerFma = 2.0 * sizeof(Lanes) / sizeof(float);
  std::vector<float> sink(threads);
  const auto start = Clock::now();
  tbb::parallel_for(0, threads, [&](int t) {
    Lanes a[kChains];
    for (int i = 0; i < kChains; ++i) a[i] = Splat(1.0f + 1e-3f * i);
    const Lanes m = Splat(0.9999999f), c = Splat(1e-7f);
    for (long k = 0; k < kIters; ++k) {
      for (int i = 0; i < kChains; ++i) a[i] = Fma(a[i], m, c);  // unrolled: kChains is a constant
    }
    float s = 0;
    for (int i = 0; i < kChains; ++i) s += First(a[i]);
    sink[t] = s;
  });
  const double seconds = std::chrono::duration<double>(Clock::now() - start).count();
  return sink[0] > 0 ? threads * kIters * kChains * kFlopsPerFma / seconds / 1e9 : 0.0;
#else
  (void)threads;
  return 0.0;
#endif
}

// Both heads, forward and backward, over the batch (each runs its own parallel loop), on their own.
double HeadsGflops(const field::FieldConfig& config, int feature_dim, double seconds) {
  field::DensityHead<float> density(feature_dim, config.heads);
  field::ColorHead<float> color(config.heads);
  std::vector<float> pd(density.param_count()), pc(color.param_count());
  density.Init(pd.data(), 1);
  color.Init(pc.data(), 2);
  const std::size_t n = kBatch;
  std::mt19937 gen(3);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  std::vector<float> feat(n * feature_dim), dir(3 * n, 0.57735f), time(n, 0.5f), d(3 * n);
  for (float& x : feat) x = u(gen);
  for (float& x : d) x = u(gen);
  std::vector<std::vector<float>> dh(density.mlp().hidden_layers()), ch(color.mlp().hidden_layers());
  std::vector<float*> dhp, chp;
  for (int k = 0; k < density.mlp().hidden_layers(); ++k) {
    dh[k].resize(n * density.mlp().hidden_dim(k));
    dhp.push_back(dh[k].data());
  }
  for (int k = 0; k < color.mlp().hidden_layers(); ++k) {
    ch[k].resize(n * color.mlp().hidden_dim(k));
    chp.push_back(ch[k].data());
  }
  std::vector<float> draw(n * density.raw_dim()), craw(4 * n), sigma(n), slv(n), in(n * color.in_dim()),
      rgb(3 * n), clv(n), gd(pd.size()), gc(pc.size()), dgeo(n * config.heads.geo_features),
      dfeat(n * feature_dim);
  const field::DropoutPass drop{true, 5, 0};
  auto run = [&] {
    density.Forward(pd.data(), {kBatch, feat.data()}, {dhp.data(), draw.data(), sigma.data(), slv.data()},
                    drop);
    color.Forward(pc.data(), {kBatch, draw.data() + 2, density.raw_dim(), dir.data(), time.data()},
                  {in.data(), chp.data(), craw.data(), rgb.data(), clv.data()}, drop);
    color.Backward(pc.data(), {kBatch, draw.data() + 2, density.raw_dim(), dir.data(), time.data()},
                   {in.data(), chp.data(), craw.data(), rgb.data(), clv.data()}, {d.data(), d.data()},
                   gc.data(), {dgeo.data()}, drop);
    density.Backward(pd.data(), {kBatch, feat.data()}, {dhp.data(), draw.data(), sigma.data(), slv.data()},
                     {d.data(), d.data(), dgeo.data()}, gd.data(), {dfeat.data()}, drop);
  };
  const double per_call = TimePerCall(seconds, run).wall;
  const double macs = static_cast<double>(density.mlp().macs_per_sample() + color.mlp().macs_per_sample());
  return 3.0 * 2.0 * macs * kBatch / per_call / 1e9;
}

void Bench(const char* name, const field::FieldConfig& config, double seconds, double peak) {
  field::Field field(config, 1);
  Batch b = MakeBatch();
  const field::SampleBatch in{kBatch, b.pos.data(), b.time.data(), b.dir.data()};
  field::FieldOutput out{b.sigma.data(), b.sigma_lv.data(), b.rgb.data(), b.rgb_lv.data()};
  const field::FieldOutputGrad grad{b.d_sigma.data(), b.d_sigma_lv.data(), b.d_rgb.data(), b.d_rgb_lv.data()};
  std::uint64_t seed = 0;
  std::printf("== %s preset ==\n%s\n", name, field::DescribeField(field).c_str());
  const Timing fb = TimePerCall(seconds, [&] {
    field.Forward(in, out, true, ++seed);
    field.Backward(in, grad);
  });
  const Timing fwd = TimePerCall(seconds, [&] { field.Forward(in, out, true, ++seed); });
  const Timing inf = TimePerCall(seconds, [&] { field.Infer(in, out, false, 0); });
  const Timing zero = TimePerCall(seconds, [&] { field.ZeroGrad(); });
  const int feature_dim = field::GridEnsemble<float>(config.grids).feature_dim();
  const double gflops = HeadsGflops(config, feature_dim, seconds);
  auto row = [](const char* what, const Timing& t) {
    std::printf("  %-17s %8.2f M samples/s  (%7.2f ms per batch; %6.2f M samples per CPU-second)\n", what,
                kBatch / t.wall / 1e6, t.wall * 1e3, kBatch / t.cpu / 1e6);
  };
  row("forward+backward", fb);
  row("forward", fwd);
  row("infer", inf);
  std::printf("  %-17s %8.3f ms\n", "zero grad", zero.wall * 1e3);
  const std::string of_peak =
      peak > 0 ? fmt::format("{:.0f}% of the {:.0f} GFLOP/s fp32 peak", 100 * gflops / peak, peak)
               : std::string("no peak: a build without AVX2 or AVX-512");
  std::printf("  heads only        %8.1f GFLOP/s  (%s; %zu MACs/sample forward)\n\n", gflops, of_peak.c_str(),
              field.head_macs_per_sample());
}

}  // namespace

int main(int argc, char** argv) {
  int threads = tbb::info::default_concurrency();
  double seconds = 2.0;
  std::string preset = "both";
  CLI::App app{"field_bench: the field's forward and backward, samples per second"};
  app.add_option("--threads", threads, "threads")->capture_default_str()->check(CLI::PositiveNumber);
  app.add_option("--seconds", seconds, "seconds per measurement")->capture_default_str();
  app.add_option("--preset", preset, "field preset")
      ->capture_default_str()
      ->check(CLI::IsMember({"cpu", "paper", "both"}));
  CLI11_PARSE(app, argc, argv);
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
  const double peak = PeakGflops(threads);
  const std::string peak_text = peak > 0 ? fmt::format("{:.0f} GFLOP/s", peak)
                                         : std::string("not measured (a build without AVX2 or AVX-512)");
  std::printf("field_bench: %d threads, batch %d samples (%d rays x %d), fp32 FMA peak %s\n\n", threads,
              kBatch, kRays, kSamplesPerRay, peak_text.c_str());
  if (preset == "cpu" || preset == "both") {
    Bench("cpu", endorecon::field::FieldConfig::Cpu(), seconds, peak);
    endorecon::field::FieldConfig still = endorecon::field::FieldConfig::Cpu();
    still.deformation.enabled = false;
    Bench("cpu, static scene", still, seconds, peak);
  }
  if (preset == "paper" || preset == "both")
    Bench("paper", endorecon::field::FieldConfig::Paper(), seconds, peak);
  return 0;
}
