// The work-precision picture (issue 6 §4): held-out error against training time for the presets and
// the ablation rows, on one plot, and the table beside it. Each variant is a whole Reconstruct run
// with the same time budget:
//   cpu            the CPU preset on the demo clip (48 frames, 160 x 128, every 8th frame held out)
//   cpu, no NLL    the same with the RGB NLL off (nll_weight 0): the ablation of the paper's loss
//   paper          the paper's preset (field and batch sizes), capped by the same budget, without
//                  depth refinement (a round of the paper's field costs more than the budget here)
//   cpu, stiff     the CPU preset on the stiff clip (synth --stiff): thin depth range, near-opaque
//                  near-black tissue, saturated speculars
// The table gives held-out tissue PSNR at 15, 30, 60 and 120 s (the last curve point at or before
// that time; curve points are measured on a subset of held-out frames, every --interval seconds) and
// the final held-out depth RMSE over the depth range (all held-out frames).
//   work_precision_bench [--budget SECONDS] [--interval SECONDS] [--out DIR] [--svg PATH]
#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "worker/engine/eval/curve_plot.h"
#include "worker/engine/reconstruct.h"
#include "worker/engine/scene/synthetic_clip.h"

namespace {

namespace fs = std::filesystem;

struct Variant {
  std::string label;
  std::string preset;
  std::string clip;       // "demo" or "stiff"
  nlohmann::json config;  // overrides on top of the bench's curve settings
};

// Held-out PSNR of the last curve point at or before `seconds`; NaN when there is none.
double PsnrAt(const nlohmann::json& curve, double seconds) {
  double psnr = NAN;
  for (const auto& point : curve) {
    if (point["seconds"].get<double>() > seconds) break;
    if (point.contains("heldout_psnr")) psnr = point["heldout_psnr"].get<double>();
  }
  return psnr;
}

}  // namespace

int main(int argc, char** argv) {
  double budget = 120, interval = 5;
  std::string out = "/tmp/endorecon-work-precision-bench", svg;
  CLI::App app{"work_precision_bench: held-out error against training time, per scene"};
  app.add_option("--budget", budget, "each run's time budget, seconds")->capture_default_str();
  app.add_option("--interval", interval, "seconds between curve points")->capture_default_str();
  app.add_option("--out", out, "scratch folder (emptied first)")->capture_default_str();
  app.add_option("--svg", svg, "the plot (default: OUT/work_precision.svg)");
  CLI11_PARSE(app, argc, argv);
  if (svg.empty()) svg = (fs::path(out) / "work_precision.svg").string();
  fs::remove_all(out);
  endorecon::scene::WriteSyntheticClip(endorecon::scene::SynthOptions{}, fs::path(out) / "demo");
  endorecon::scene::SynthOptions stiff;
  stiff.stiff = true;
  endorecon::scene::WriteSyntheticClip(stiff, fs::path(out) / "stiff");

  const std::vector<Variant> variants = {{"cpu", "cpu", "demo", nlohmann::json::object()},
                                         {"cpu, no NLL", "cpu", "demo", {{"nll_weight", 0.0}}},
                                         // A depth-refinement round of the paper's field renders every
                                         // training frame: minutes on 2 cores, more than the budget.
                                         {"paper", "paper", "demo", {{"depth_refine_every", 0.0}}},
                                         {"cpu, stiff clip", "cpu", "stiff", nlohmann::json::object()}};
  std::vector<endorecon::eval::CurveSeries> series;
  std::vector<nlohmann::json> results;
  for (std::size_t v = 0; v < variants.size(); ++v) {
    const Variant& variant = variants[v];
    const fs::path dir = fs::path(out) / ("run" + std::to_string(v));
    fs::create_directories(dir);
    nlohmann::json config = variant.config;
    config["curve_interval_s"] = interval;
    config["curve_frames"] = 3;

    endorecon::ReconstructOptions options;
    options.clip_dir = (fs::path(out) / variant.clip).string();
    options.out_dir = (dir / "result").string();
    options.config = config;
    options.preset = variant.preset;
    options.holdout = 8;
    options.iterations = 1000000;
    options.time_budget_s = budget;
    std::fprintf(stderr, "running %s (%g s)\n", variant.label.c_str(), budget);
    endorecon::Reconstruct(options, {});

    std::ifstream in(dir / "result" / "metrics.json");
    results.push_back(nlohmann::json::parse(in));
    endorecon::eval::CurveSeries line;
    line.label = variant.label;
    for (const auto& point : results.back()["curve"]) {
      line.seconds.push_back(point["seconds"].get<double>());
      line.psnr.push_back(point.value("heldout_psnr", NAN));
    }
    series.push_back(std::move(line));
  }
  endorecon::eval::CurvePlotOptions plot;
  plot.title = "Work-precision: held-out tissue PSNR against training time";
  endorecon::eval::WriteCurveSvg(svg, series, plot);

  const double marks[] = {15, 30, 60, 120};
  std::printf(
      "| variant | PSNR @15 s | @30 s | @60 s | @120 s | iterations | final PSNR | final depth RMSE / range "
      "|\n");
  std::printf("|---|---|---|---|---|---|---|---|\n");
  for (std::size_t v = 0; v < variants.size(); ++v) {
    const auto& metrics = results[v];
    std::printf("| %s |", variants[v].label.c_str());
    for (double mark : marks) {
      const double psnr = mark <= budget ? PsnrAt(metrics["curve"], mark) : NAN;
      if (std::isnan(psnr)) {
        std::printf(" - |");
      } else {
        std::printf(" %.2f |", psnr);
      }
    }
    std::printf(" %d | %.2f | %.4f |\n", metrics["iterations"].get<int>(),
                metrics["heldout"]["image"]["psnr_tissue"]["mean"].get<double>(),
                metrics["heldout"]["depth"]["rmse_relative"]["mean"].get<double>());
  }
  std::printf("plot: %s\n", svg.c_str());
  return 0;
}
