// The ablation of issue 4 (the paper's tables) on the synthetic demo clip (48 frames, 160 x 128,
// every 8th frame held out), each row trained for the same time budget with the CPU preset:
//   (a) EndoNeRF-like: NeRF's positional encoding (10 frequencies) into a 4 x 128 density MLP in
//       place of the hash grids and temporal blend; plain L2 (no NLL), no adaptive sampling
//   (b) hash ensemble + temporal blending, plain L2 (no NLL), no adaptive sampling
//   (c) + uncertainty (the preset's NLL)
//   (d) + uncertainty-guided adaptive sampling (the CPU preset as it is)
// Every row keeps the 4D-grid deformation (EndoNeRF's is an MLP), so (a) against (b) isolates the
// encoder. Reports held-out PSNR, SSIM, depth error, the calibration of the uncertainty (Pearson,
// Spearman, AUSE; all frames and held-out) and wall time, as a markdown table. --override JSON is
// config keys applied to every row under the row's own (e.g. another dropout rate for all four).
//   ablation_bench [--budget SECONDS] [--threads N] [--out DIR] [--rows abcd] [--override JSON]
#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "worker/engine/reconstruct.h"
#include "worker/engine/scene/synthetic_clip.h"

namespace {

struct Row {
  const char* name;
  nlohmann::json config;
};

double At(const nlohmann::json& json, const char* pointer) {
  const nlohmann::json::json_pointer p(pointer);
  return json.contains(p) && json.at(p).is_number() ? json.at(p).get<double>() : NAN;
}

}  // namespace

int main(int argc, char** argv) {
  double budget = 120;
  int threads = 0;
  std::string out = "/tmp/endorecon-ablation-bench";
  std::string row_letters = "abcd";
  std::string override_text = "{}";
  CLI::App app{"ablation_bench: the paper's ablation rows on the demo clip"};
  app.add_option("--budget", budget, "each run's time budget, seconds")->capture_default_str();
  app.add_option("--threads", threads, "threads per run (0: all)")->capture_default_str();
  app.add_option("--out", out, "scratch folder")->capture_default_str();
  app.add_option("--rows", row_letters, "which rows, by letter")->capture_default_str();
  app.add_option("--override", override_text, "training keys over the preset, JSON")->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  const nlohmann::json overrides = nlohmann::json::parse(override_text);
  namespace fs = std::filesystem;
  const fs::path root(out);
  fs::create_directories(root);
  endorecon::scene::WriteSyntheticClip(endorecon::scene::SynthOptions{}, root / "clip");
  const std::vector<Row> all_rows = {
      {"(a) positional encoding + MLP (EndoNeRF-like), L2",
       {{"nll_weight", 0.0},
        {"adaptive_sampling", false},
        {"field",
         {{"encoding", "frequency"},
          {"frequencies", 10},
          {"heads", {{"density_hidden", {128, 128, 128, 128}}}}}}}},
      {"(b) hash ensemble + blending, L2", {{"nll_weight", 0.0}, {"adaptive_sampling", false}}},
      {"(c) + uncertainty (NLL)", {{"adaptive_sampling", false}}},
      {"(d) + adaptive sampling", nlohmann::json::object()},
  };
  std::vector<Row> rows;
  for (char c : row_letters) {
    if (c >= 'a' && c <= 'd') rows.push_back(all_rows[std::size_t(c - 'a')]);
  }
  std::printf(
      "| row | held-out PSNR (tissue) | held-out SSIM (tissue) | held-out depth RMSE / range | Pearson | "
      "Spearman | AUSE | held-out Spearman | held-out AUSE | iterations | train s | wall s |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const fs::path dir = root / ("row" + std::to_string(i));
    fs::create_directories(dir);
    nlohmann::json config = overrides;
    config.merge_patch(rows[i].config);
    endorecon::ReconstructOptions options;
    options.clip_dir = (root / "clip").string();
    options.out_dir = (dir / "result").string();
    options.config = config;
    options.holdout = 8;
    options.iterations = 1000000;  // the time budget ends every run
    options.time_budget_s = budget;
    options.threads = threads;
    const auto start = std::chrono::steady_clock::now();
    const auto summary = endorecon::Reconstruct(options, {});
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    nlohmann::json m;
    std::ifstream(summary.metrics_path) >> m;
    // Calibration over all frames: the frame-count-weighted mean of the two splits' means.
    const double nt = At(m, "/train/calibration/spearman/count"),
                 nh = At(m, "/heldout/calibration/spearman/count");
    const auto both = [&](const char* train, const char* heldout) {
      return (At(m, train) * nt + At(m, heldout) * nh) / (nt + nh);
    };
    std::printf("| %s | %.2f | %.4f | %.4f | %.3f | %.3f | %.3f | %.3f | %.3f | %d | %.0f | %.0f |\n",
                rows[i].name, At(m, "/heldout/image/psnr_tissue/mean"),
                At(m, "/heldout/image/ssim_tissue/mean"), At(m, "/heldout/depth/rmse_relative/mean"),
                both("/train/calibration/pearson/mean", "/heldout/calibration/pearson/mean"),
                both("/train/calibration/spearman/mean", "/heldout/calibration/spearman/mean"),
                both("/train/calibration/ause/mean", "/heldout/calibration/ause/mean"),
                At(m, "/heldout/calibration/spearman/mean"), At(m, "/heldout/calibration/ause/mean"),
                summary.iterations, summary.train_seconds, wall);
    std::fflush(stdout);
  }
  return 0;
}
