// endorecon-worker render: renders colour and depth from a results folder's trained model for any
// cameras at any times (a transforms.json-style list), e.g. the other eye of a stereo endoscope.
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <memory>

#include "worker/engine/eval/exports.h"
#include "worker/engine/render/frame_renderer.h"
#include "worker/engine/scene/camera_list.h"
#include "worker/engine/train/checkpoint.h"
#include "worker/runtime/commands.h"

namespace endorecon::worker {

Command AddRenderCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand("render", "render any cameras at any times from a results folder");
  struct Args {
    std::string result, cameras, out;
  };
  auto args = std::make_shared<Args>();
  cmd->add_option("result", args->result, "results folder of `reconstruct` (holds model/model.bin)")->required();
  cmd->add_option("--cameras", args->cameras, "transforms.json-style camera list with per-camera time")->required();
  cmd->add_option("-o,--out", args->out, "output folder (rgb/, depth/)")->required();
  return [args] {
    const train::Model model = train::ReadModel(std::filesystem::path(args->result) / "model" / "model.bin");
    const auto cameras = scene::ReadCameraList(args->cameras);
    render::FrameRenderSettings settings;
    settings.near = model.near;
    settings.far = model.far;
    settings.coarse_samples = model.config.eval_coarse_samples;
    settings.fine_samples = model.config.eval_fine_samples;
    settings.floor = model.config.eval_floor;
    render::FrameRenderer renderer(*model.field, model.box, settings);
    const std::filesystem::path out(args->out);
    std::filesystem::create_directories(out / "rgb");
    std::filesystem::create_directories(out / "depth");
    const double scale = eval::DepthPngScale(model.far);
    for (std::size_t i = 0; i < cameras.size(); ++i) {
      const auto& view = cameras[i];
      const auto frame = renderer.Render(view.camera, view.time);
      eval::WritePng8(out / "rgb" / eval::FrameFileName(int(i), ".png"), frame.rgb, frame.width, frame.height);
      eval::WriteDepthNpy(out / "depth" / eval::FrameFileName(int(i), ".npy"), frame.depth, frame.width, frame.height);
      eval::WriteDepthPng16(out / "depth" / eval::FrameFileName(int(i), ".png"), frame.depth, frame.width,
                            frame.height, scale);
    }
    spdlog::info("rendered {} views into {} (depth PNG scale {})", cameras.size(), args->out, scale);
    return 0;
  };
}

}  // namespace endorecon::worker
