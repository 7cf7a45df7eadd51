// gpu_train_bench: training on a GPU against the CPU, in the same run (issue 13 §6). The demo clip
// (synth's defaults: 48 frames, 160 x 128, camera noise; every 8th frame held out) is made in memory
// and trained with the cpu preset on --device for --seconds and on the CPU for --cpu-seconds (the
// same work on both: their samples/s ratio), then with --preset (gpu by default; skipped when its
// settings are the cpu preset's, as the gpu preset's are since 2026-12-04) on
// --device for --seconds again (its time to the CPU's last PSNR is the target); every
// --probe-s seconds of training the held-out tissue PSNR is measured with the run's curve probe
// (eval/curve_probe.h: every s-th pixel of up to 6 held-out frames, one dropout-off render on the
// device that trains; the probes' time is not counted as training). Prints the curves, each run's
// training samples per second, its ratio to the CPU's, and how long each GPU run took to reach the
// CPU's last PSNR. With --big-seconds S it then trains a 640 x 512, 160-frame clip (synth --seed 3)
// with --preset on --device for S seconds and prints its curve. Nothing is read from or written to files: the
// binary travels to bare GPU machines with scripts/gpu-check, whose DIR/run calls it.
// Two sweeps for sizing, both optional: --override JSON (repeatable) trains --preset once per JSON
// (train_config.h's ApplyJson keys, e.g. '{"rays_per_batch":4096}') instead of once as it is, and
// --cpu-threads N (repeatable) runs the CPU curve once per thread count (0: every core; the last
// one's PSNR is the target). --seconds 0 skips the demo clip's runs, --cpu-seconds 0 the CPU's; the
// big clip is trained once per --override too. --render-chunks N (repeatable) times, after the demo
// clip's first run on --device, full held-out renders with the results' uncertainty at N rays a chunk.
//   gpu_train_bench [--device cuda:0] [--preset gpu] [--seconds 30] [--cpu-seconds 90]
//                   [--probe-s 5] [--big-seconds 0] [--override JSON]... [--cpu-threads N]...
//                   [--render-chunks N]...
#include <tbb/global_control.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <exception>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "worker/engine/eval/curve_probe.h"
#include "worker/engine/render/frame_renderer.h"
#include "worker/engine/run_config.h"
#include "worker/engine/scene/synthetic_frames.h"
#include "worker/engine/train/render_settings.h"
#include "worker/engine/train/scene_fit.h"
#include "worker/engine/train/train_config.h"
#include "worker/engine/train/trainer.h"

namespace {

using namespace endorecon;
using Clock = std::chrono::steady_clock;

struct Point {
  double seconds = 0;  // of training
  int iteration = 0;
  double psnr = 0;
};

struct Curve {
  std::string device;
  std::vector<Point> points;
  double samples_per_second = 0;
};

// Renders the held-out frames in full with the results' Monte Carlo uncertainty once per chunk size
// (rays a RenderChunk call), after one warm-up frame, and prints the time a frame and how far each
// size's images and maps are from the first size's (other chunks draw other dropout masks).
void TimeRenders(train::Trainer& trainer, const scene::Clip& clip, const train::TrainConfig& config,
                 const render::RenderBackendFactory& backend, const std::vector<int>& heldout,
                 const std::vector<int>& chunks) {
  trainer.SyncField();
  std::vector<render::RenderedFrame> first;
  for (const int chunk : chunks) {
    render::FrameRenderSettings settings = train::UncertaintyRenderSettings(config, clip.near, clip.far, 1);
    settings.rays_per_chunk = chunk;
    render::FrameRenderer renderer(trainer.field(), trainer.box(), settings, backend);
    renderer.SetOccupancy(&trainer.occupancy());
    renderer.Render(clip.cameras[heldout[0]], clip.times[heldout[0]]);
    std::vector<render::RenderedFrame> frames;
    const auto start = Clock::now();
    for (const int f : heldout) frames.push_back(renderer.Render(clip.cameras[f], clip.times[f]));
    const double ms = 1e3 * std::chrono::duration<double>(Clock::now() - start).count() / heldout.size();
    if (first.empty()) first = frames;
    double rgb_off = 0, uncertainty = 0, first_uncertainty = 0;
    std::size_t values = 0, pixels = 0;
    for (std::size_t i = 0; i < frames.size(); ++i) {
      for (std::size_t v = 0; v < frames[i].rgb.size(); ++v)
        rgb_off += std::fabs(frames[i].rgb[v] - first[i].rgb[v]);
      for (std::size_t p = 0; p < frames[i].uncertainty.size(); ++p) {
        uncertainty += frames[i].uncertainty[p];
        first_uncertainty += first[i].uncertainty[p];
      }
      values += frames[i].rgb.size();
      pixels += frames[i].uncertainty.size();
    }
    std::printf(
        "  render, %5d rays a chunk: %7.1f ms a frame (%zu frames, %d x %d, %d dropout passes); colour off "
        "the first size's by %.2e on average, mean uncertainty %.4g (first size %.4g)\n",
        chunk, ms, heldout.size(), clip.width, clip.height, settings.mc_passes, rgb_off / values,
        uncertainty / pixels, first_uncertainty / pixels);
    std::fflush(stdout);
  }
}

// Trains `clip` on `device` for `seconds` of steps, probing the held-out PSNR every `probe_s`; then
// times renders at each of `render_chunks` (none: no renders).
Curve Train(const scene::Clip& clip, train::TrainConfig config, const std::string& device, double seconds,
            double probe_s, const std::vector<int>& render_chunks = {}) {
  const FrameSplit split = SplitFrames(clip.frame_count(), 8);
  train::FitToScene(clip, config, split.train);
  const DeviceBackends backends = BackendsFor(device);
  train::Trainer trainer(clip, config, split.train, /*seed=*/1, backends.step, backends.render);
  trainer.StartDeformation();  // the flow start (host work, once a run) is not a training step
  render::FrameRenderer renderer(trainer.field(), trainer.box(),
                                 train::EvalRenderSettings(config, clip.near, clip.far), backends.render);
  renderer.SetOccupancy(&trainer.occupancy());
  const eval::CurveProbe probe(clip, split.heldout, 6);
  Curve curve;
  curve.device = trainer.device();
  double trained = 0, next_probe = probe_s;
  long long samples = 0;
  const auto measure = [&] {
    trainer.SyncField();
    curve.points.push_back({trained, trainer.iteration(), probe.Measure(renderer).psnr});
    std::printf("  %-28s %8.1f s %8d it %8.2f dB\n", curve.device.c_str(), trained, trainer.iteration(),
                curve.points.back().psnr);
    std::fflush(stdout);
  };
  while (trained < seconds) {
    const auto start = Clock::now();
    samples += trainer.Step(trained / seconds).samples;
    trained += std::chrono::duration<double>(Clock::now() - start).count();
    if (trained >= next_probe) {
      measure();
      next_probe += probe_s;
    }
  }
  if (curve.points.empty() || curve.points.back().iteration != trainer.iteration()) measure();
  curve.samples_per_second = samples / trained;
  std::printf("  %-28s %.3g training samples/s over %d iterations\n", curve.device.c_str(),
              curve.samples_per_second, trainer.iteration());
  if (!render_chunks.empty())
    TimeRenders(trainer, clip, config, backends.render, split.heldout, render_chunks);
  return curve;
}

// The first training time at which `curve` reaches `psnr`; negative when it never does.
double TimeToReach(const Curve& curve, double psnr) {
  for (const Point& point : curve.points) {
    if (point.psnr >= psnr) return point.seconds;
  }
  return -1;
}

}  // namespace

int main(int argc, char** argv) {
  std::string device = "cuda:0", preset = "gpu";
  double seconds = 30, cpu_seconds = 90, probe_s = 5, big_seconds = 0;
  std::vector<std::string> overrides;
  std::vector<int> cpu_threads = {0}, render_chunks;
  CLI::App app{"gpu_train_bench: training on a GPU against the CPU, in the same run"};
  app.add_option("--device", device, "the GPU: cuda:N (cpu to try the bench without one)")
      ->capture_default_str();
  app.add_option("--preset", preset, "the second GPU run's preset")
      ->capture_default_str()
      ->check(CLI::IsMember({"cpu", "gpu", "paper"}));
  app.add_option("--seconds", seconds, "training seconds of each GPU run")->capture_default_str();
  app.add_option("--cpu-seconds", cpu_seconds, "training seconds of the CPU run")->capture_default_str();
  app.add_option("--probe-s", probe_s, "training seconds between curve points")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  app.add_option("--big-seconds", big_seconds, "training seconds on the 640 x 512 x 160 clip (0: none)")
      ->capture_default_str();
  app.add_option("--override", overrides, "train --preset once per JSON override (repeatable)");
  app.add_option("--cpu-threads", cpu_threads, "run the CPU curve once per thread count (0: every core)")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--render-chunks", render_chunks,
                 "after the demo clip's first GPU run, time held-out renders with uncertainty at each of "
                 "these rays a chunk (repeatable)")
      ->check(CLI::Range(1, 1 << 20));
  CLI11_PARSE(app, argc, argv);
  try {
    BackendsFor(device);  // refuses a device that is not there before any clip is made
    // The configs to sweep, each --preset with one override, made before anything trains: an override
    // that is not JSON, or names no key, is refused at once.
    if (overrides.empty()) overrides.push_back("{}");
    std::vector<train::TrainConfig> variants;
    for (const std::string& json : overrides) {
      variants.push_back(train::TrainConfig::Preset(preset));
      train::ApplyJson(nlohmann::json::parse(json), variants.back());
    }
    if (seconds > 0) {
      const scene::Clip demo = scene::MakeSyntheticClip(scene::SynthOptions{});
      std::printf("gpu_train_bench: demo clip (48 frames, 160 x 128, noisy), preset cpu on both\n");
      const train::TrainConfig cpu_preset = train::TrainConfig::Preset("cpu");
      const Curve same = Train(demo, cpu_preset, device, seconds, probe_s, render_chunks);
      Curve cpu;
      for (const int threads : cpu_seconds > 0 ? cpu_threads : std::vector<int>{}) {
        std::unique_ptr<tbb::global_control> limit;
        if (threads > 0) {
          limit =
              std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, threads);
        }
        std::printf("gpu_train_bench: demo clip, preset cpu on the cpu, %s threads\n",
                    threads > 0 ? std::to_string(threads).c_str() : "all");
        cpu = Train(demo, cpu_preset, "cpu", cpu_seconds, probe_s);
      }
      const auto report = [&](const Curve& gpu, const std::string& gpu_preset) {
        if (cpu.points.empty()) return;  // --cpu-seconds 0: nothing to compare with
        const double target = cpu.points.back().psnr, reached = TimeToReach(gpu, target);
        char when[32] = "(not reached)";
        if (reached >= 0) std::snprintf(when, sizeof when, "%.1f s", reached);
        std::printf(
            "gpu_train_bench: %s preset %s %.3g samples/s, cpu preset cpu %.3g samples/s: %.1fx; the "
            "cpu's %.2f dB after %.0f s reached on the gpu after %s\n",
            gpu.device.c_str(), gpu_preset.c_str(), gpu.samples_per_second, cpu.samples_per_second,
            gpu.samples_per_second / cpu.samples_per_second, target, cpu_seconds, when);
      };
      report(same, "cpu");
      // A variant that is the cpu preset under another name (today's gpu preset) was trained above.
      const auto settings = [](train::TrainConfig config) {
        config.preset.clear();
        return train::ToJson(config);
      };
      for (std::size_t v = 0; v < variants.size(); ++v) {
        if (settings(variants[v]) == settings(cpu_preset)) continue;
        std::printf("gpu_train_bench: demo clip, preset %s %s on %s\n", preset.c_str(), overrides[v].c_str(),
                    device.c_str());
        report(Train(demo, variants[v], device, seconds, probe_s), preset + " " + overrides[v]);
      }
    }
    if (big_seconds > 0) {
      scene::SynthOptions big;
      big.frames = 160;
      big.width = 640;
      big.height = 512;
      big.seed = 3;
      const scene::Clip clip = scene::MakeSyntheticClip(big);
      for (std::size_t v = 0; v < variants.size(); ++v) {
        const char* json = overrides[v].c_str();
        std::printf("gpu_train_bench: 640 x 512, 160 frames, preset %s %s\n", preset.c_str(), json);
        const Curve large = Train(clip, variants[v], device, big_seconds, probe_s * 4);
        std::printf(
            "gpu_train_bench: big clip, preset %s %s: %.3g samples/s, held-out %.2f dB after %.0f s\n",
            preset.c_str(), json, large.samples_per_second, large.points.back().psnr, big_seconds);
      }
    }
  } catch (const std::exception& e) {  // a device that is not there, an override that is not JSON
    std::fprintf(stderr, "gpu_train_bench: %s\n", e.what());
    return 1;
  }
  return 0;
}
