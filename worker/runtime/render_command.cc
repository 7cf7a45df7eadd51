// endorecon-worker render: renders colour, depth and uncertainty from a results folder's trained model for
// any cameras at any times (a transforms.json-style list), e.g. the other eye of a stereo endoscope.
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdint>
#include <limits>
#include <memory>
#include <nlohmann/json.hpp>

#include "common/error.h"
#include "common/file_write.h"
#include "common/output_folder.h"
#include "worker/engine/eval/clip_evaluator.h"
#include "worker/engine/eval/exports.h"
#include "worker/engine/eval/model_uncertainty.h"
#include "worker/engine/eval/report.h"
#include "worker/engine/render/frame_renderer.h"
#include "worker/engine/run_config.h"
#include "worker/engine/scene/camera_list.h"
#include "worker/engine/train/checkpoint.h"
#include "worker/engine/train/render_settings.h"
#include "worker/engine/train/trainer.h"
#include "worker/runtime/commands.h"
#include "worker/runtime/progress_line.h"

namespace endorecon::worker {

Command AddRenderCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand("render", "render any cameras at any times from a results folder");
  struct Args {
    std::string result, cameras, out, device = "cpu";
    int mc_passes = -1;
  };
  auto args = std::make_shared<Args>();
  cmd->add_option("result", args->result, "results folder of `reconstruct` (holds model/model.bin)")
      ->required();
  cmd->add_option("--cameras", args->cameras, "transforms.json-style camera list with per-camera time")
      ->required();
  cmd->add_option("-o,--out", args->out, "output folder (rgb/, depth/, uncertainty/)")->required();
  cmd->add_option("--mc-passes", args->mc_passes,
                  "dropout passes for the uncertainty maps (default: the model's, 0: no uncertainty)")
      ->check(CLI::Range(0, 64));  // a configuration's mc_passes bound
  cmd->add_option("--device", args->device, "where the views are rendered: cpu or cuda:N")
      ->capture_default_str();
  return [args] {
    // Refuses, naming the reason, a device this build or machine cannot use (before reading anything).
    const render::RenderBackendFactory backend = BackendsFor(args->device).render;
    const std::filesystem::path result(args->result);
    if (!std::filesystem::is_directory(result))
      FailInvalid(args->result + ": no such folder (render takes the results folder of a reconstruction)");
    if (!std::filesystem::exists(result / "model" / "model.bin")) {
      FailInvalid(args->result + ": not a reconstruction's results folder (it has no model/model.bin" +
                  (std::filesystem::exists(result / "render.json") ? "; it holds rendered views)" : ")"));
    }
    const train::Model model = train::ReadModel(result / "model" / "model.bin");
    const auto cameras = scene::ReadCameraList(args->cameras);
    auto settings = train::UncertaintyRenderSettings(model.config, model.near, model.far, 0);
    if (args->mc_passes >= 0) settings.mc_passes = args->mc_passes;
    render::FrameRenderer renderer(*model.field, model.box, settings, backend);
    const render::OccupancyGrid occupancy = train::BuildOccupancy(*model.field, model.config);
    renderer.SetOccupancy(&occupancy);
    const std::filesystem::path out(args->out);
    CheckOutputFolder(out, args->result, "the results folder it renders from", ResultsKind::kRender);
    ClearEarlierResults(out, ResultsKind::kRender, {args->cameras});
    const bool uncertainty = settings.mc_passes > 0;
    for (const char* sub : {"rgb", "depth", "uncertainty"}) {
      if (uncertainty || sub != std::string_view("uncertainty"))
        std::filesystem::create_directories(out / sub);
    }
    const double scale = eval::DepthPngScale(model.far);
    // Written first, so the folder is known as a render's before its views are (output_folder.h), and
    // again with the heat maps' scales once they are known.
    nlohmann::json info = eval::UncertaintySettings(settings);
    info["depth_png_scale"] = scale;
    // Where the views came from and were rendered, for the page (report.html names both).
    info["results"] = std::filesystem::absolute(args->result).lexically_normal().string();
    info["device"] = renderer.device();
    WriteFile(out / "render.json", info.dump(2), "render description");
    // The heat maps share one scale over all views, so they are written once every view is rendered.
    std::vector<std::vector<float>> totals, models;
    // The heat maps are drawn grey where a view sees no surface (its depth 0, grey on the report): black read
    // as "most certain" (a camera pointed away from the tissue; found 2026-12-07). The .npy keep the values.
    std::vector<std::vector<std::uint8_t>> surfaces;
    for (std::size_t i = 0; i < cameras.size(); ++i) {
      const auto& view = cameras[i];
      auto frame = renderer.Render(view.camera, view.time);
      // 2,000 views rendered for minutes without a word (found 2026-12-06).
      ShowProgress(fmt::format(" rendered {}/{} views ", i + 1, cameras.size()));
      const int w = frame.width, h = frame.height;
      eval::ClearDepthWithoutSurface(frame.depth, frame.opacity);
      std::vector<std::uint8_t> surface(frame.opacity.size());
      for (std::size_t p = 0; p < surface.size(); ++p) surface[p] = frame.opacity[p] >= eval::kSurfaceOpacity;
      // A view that sees nothing (a camera far away, or turned from the scene) was written blank
      // without a word (found 2026-12-07).
      if (std::none_of(surface.begin(), surface.end(), [](std::uint8_t s) { return s != 0; })) {
        spdlog::warn(
            "view {} sees no surface of the scene (every pixel's opacity under {}): is its camera "
            "turned away from the scene, or outside it? Its images are blank and its depth 0",
            i, eval::kSurfaceOpacity);
      }
      eval::WritePng8(out / "rgb" / eval::FrameFileName(int(i), ".png"), frame.rgb, w, h);
      eval::WriteDepthNpy(out / "depth" / eval::FrameFileName(int(i), ".npy"), frame.depth, w, h);
      eval::WriteDepthPng16(out / "depth" / eval::FrameFileName(int(i), ".png"), frame.depth, w, h, scale);
      if (frame.uncertainty.empty()) continue;
      const auto path = [&](const char* suffix) {
        return out / "uncertainty" / eval::FrameFileName(int(i), suffix);
      };
      eval::WriteDepthNpy(path(".npy"), frame.uncertainty, w, h);
      eval::WriteDepthNpy(path("_aleatoric.npy"), frame.aleatoric, w, h);
      eval::WriteDepthNpy(path("_epistemic.npy"), frame.epistemic, w, h);
      models.push_back(eval::ModelUncertainty(frame.rgb, frame.aleatoric, frame.epistemic, {}));
      eval::WriteDepthNpy(path("_model.npy"), models.back(), w, h);
      totals.push_back(std::move(frame.uncertainty));
      surfaces.push_back(std::move(surface));
    }
    EndProgress();
    // NaN (grey, and left out of the scale) where there is no surface.
    for (std::size_t i = 0; i < totals.size(); ++i) {
      for (std::size_t p = 0; p < totals[i].size(); ++p) {
        if (surfaces[i][p]) continue;
        totals[i][p] = std::numeric_limits<float>::quiet_NaN();
        models[i][p] = std::numeric_limits<float>::quiet_NaN();
      }
    }
    const double heat = eval::HeatmapUpperBound(totals), model_heat = eval::HeatmapUpperBound(models);
    for (std::size_t i = 0; i < totals.size(); ++i) {
      const int w = cameras[i].camera.width, h = cameras[i].camera.height;
      eval::WriteHeatmapPng(out / "uncertainty" / eval::FrameFileName(int(i), ".png"), totals[i], w, h, 0.0,
                            heat);
      eval::WriteHeatmapPng(out / "uncertainty" / eval::FrameFileName(int(i), "_model.png"), models[i], w, h,
                            0.0, model_heat);
    }
    if (uncertainty) {
      info["heatmap_scale"] = {{"uncertainty", {0.0, heat}}, {"model", {0.0, model_heat}}};
      WriteFile(out / "render.json", info.dump(2), "render description");
    }
    // The views' cameras and times travel with them (the report back-projects the depth through them).
    const auto cameras_copy = out / "cameras.json";
    if (!std::filesystem::exists(cameras_copy) || !std::filesystem::equivalent(args->cameras, cameras_copy)) {
      std::filesystem::copy_file(args->cameras, cameras_copy,
                                 std::filesystem::copy_options::overwrite_existing);
    }
    eval::WriteReport(out);
    spdlog::info(
        "rendered {} view{} on {} into {} (depth PNG scale {}{})", cameras.size(),
        cameras.size() == 1 ? "" : "s", renderer.device(), args->out, scale,
        uncertainty ? fmt::format(", uncertainty heat-map scale [0, {}]", heat) : ", no uncertainty");
    return 0;
  };
}

}  // namespace endorecon::worker
