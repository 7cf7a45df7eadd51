#include "worker/engine/eval/clip_evaluator.h"

#include <nlohmann/json.hpp>

#include "worker/engine/eval/calibration.h"
#include "worker/engine/eval/depth_error.h"
#include "worker/engine/eval/exports.h"
#include "worker/engine/eval/image_metrics.h"
#include "worker/engine/eval/pixel_error.h"
#include "worker/engine/eval/point_cloud.h"
#include "worker/engine/eval/surface_mesh.h"
#include "worker/engine/eval/video_writer.h"

namespace endorecon::eval {

const std::vector<std::uint8_t>& EvaluationMask(const scene::Clip& clip, int frame) {
  static const std::vector<std::uint8_t> kNone;
  if (!clip.eval_mask.empty()) return clip.eval_mask[frame];
  if (!clip.tool_mask.empty()) return clip.tool_mask[frame];
  return kNone;
}

namespace {

nlohmann::json SplitMetrics(const scene::Clip& clip, const std::vector<int>& frames,
                            const std::vector<ImageMetrics>& images, const std::vector<DepthError>& depths,
                            const std::vector<Calibration>& calibration) {
  std::vector<ImageMetrics> image_subset;
  std::vector<DepthError> depth_subset;
  std::vector<Calibration> calibration_subset;
  for (int f : frames) {
    image_subset.push_back(images[f]);
    if (!depths.empty()) depth_subset.push_back(depths[f]);
    if (!calibration.empty()) calibration_subset.push_back(calibration[f]);
  }
  nlohmann::json json;
  json["frames"] = frames;
  json["image"] = ToJson(std::span<const ImageMetrics>(image_subset));
  if (!clip.gt_depth.empty()) json["depth"] = ToJson(std::span<const DepthError>(depth_subset));
  if (!calibration.empty()) json["calibration"] = ToJson(std::span<const Calibration>(calibration_subset));
  return json;
}

// The uncertainty maps of every frame are kept until all are rendered, so one heat-map scale
// serves the whole clip.
struct UncertaintyMaps {
  std::vector<std::vector<float>> total, error;

  void Write(const std::filesystem::path& out_dir,
             const std::vector<render::RenderedFrame>& aleatoric_epistemic, int w, int h,
             nlohmann::json& json) const {
    const double scale = HeatmapUpperBound(total);
    const double error_scale = HeatmapUpperBound(error);
    for (const char* sub : {"uncertainty", "error"}) std::filesystem::create_directories(out_dir / sub);
    for (std::size_t f = 0; f < total.size(); ++f) {
      const int i = int(f);
      const auto& frame = aleatoric_epistemic[f];
      WriteDepthNpy(out_dir / "uncertainty" / FrameFileName(i, ".npy"), total[f], w, h);
      WriteDepthNpy(out_dir / "uncertainty" / FrameFileName(i, "_aleatoric.npy"), frame.aleatoric, w, h);
      WriteDepthNpy(out_dir / "uncertainty" / FrameFileName(i, "_epistemic.npy"), frame.epistemic, w, h);
      WriteHeatmapPng(out_dir / "uncertainty" / FrameFileName(i, ".png"), total[f], w, h, 0.0, scale);
      WriteHeatmapPng(out_dir / "error" / FrameFileName(i, ".png"), error[f], w, h, 0.0, error_scale);
    }
    json["heatmap_scale"] = {{"uncertainty", {0.0, scale}}, {"error", {0.0, error_scale}}};
  }
};

}  // namespace

nlohmann::json UncertaintySettings(const render::FrameRenderSettings& settings) {
  return {{"mc_passes", settings.mc_passes},
          {"lambda", settings.color_weight},
          {"variance_eps", settings.variance_eps},
          {"error_measure", "per-pixel RMSE over the RGB channels, colours in [0, 1] (eval::PixelRmse)"},
          {"score", "S_ray = sum_j w_j (var_sigma,j + lambda var_c,j) / sum_j w_j, raw variances"}};
}

nlohmann::json EvaluateClip(const scene::Clip& clip, render::FrameRenderer& renderer,
                            const ClipEvaluation& what, const std::filesystem::path& out_dir) {
  const int count = clip.frame_count();
  const int w = clip.width, h = clip.height;
  const double depth_scale = DepthPngScale(clip.far);
  if (what.write_files) {
    for (const char* sub : {"rgb", "depth", "pointcloud"}) std::filesystem::create_directories(out_dir / sub);
  }
  std::vector<ImageMetrics> images(count);
  std::vector<DepthError> depths(clip.gt_depth.empty() ? 0 : count);
  std::vector<std::vector<float>> video;
  const bool uncertain = renderer.settings().mc_passes > 0;
  std::vector<Calibration> calibration(uncertain ? count : 0);
  UncertaintyMaps maps;
  std::vector<render::RenderedFrame> components;  // aleatoric and epistemic maps only
  for (int f = 0; f < count; ++f) {
    render::RenderedFrame frame = renderer.Render(clip.cameras[f], clip.times[f]);
    const auto& mask = EvaluationMask(clip, f);
    images[f] = MeasureImage(frame.rgb, clip.rgb[f], mask, w, h);
    if (uncertain) {
      std::vector<float> error = PixelRmse(frame.rgb, clip.rgb[f], w, h);
      calibration[f] = MeasureCalibration(frame.uncertainty, error, mask);
      if (what.write_files) {
        maps.total.push_back(std::move(frame.uncertainty));
        maps.error.push_back(std::move(error));
        render::RenderedFrame parts;
        parts.aleatoric = std::move(frame.aleatoric);
        parts.epistemic = std::move(frame.epistemic);
        components.push_back(std::move(parts));
      }
    }
    if (!depths.empty())
      depths[f] = MeasureDepth(frame.depth, clip.gt_depth[f], mask, w, h, clip.near, clip.far);
    if (what.write_files) {
      WritePng8(out_dir / "rgb" / FrameFileName(f, ".png"), frame.rgb, w, h);
      WriteDepthNpy(out_dir / "depth" / FrameFileName(f, ".npy"), frame.depth, w, h);
      WriteDepthPng16(out_dir / "depth" / FrameFileName(f, ".png"), frame.depth, w, h, depth_scale);
      WritePly(
          out_dir / "pointcloud" / FrameFileName(f, ".ply"),
          BackProject(clip.cameras[f], frame.depth, frame.rgb, clip.has_masks() ? clip.tool_mask[f] : mask));
      if (f == 0) {  // the canonical frame's surface (t = 0)
        WriteSurfaceMesh(out_dir, TriangulateDepth(clip.cameras[f], frame.depth, frame.rgb,
                                                   clip.has_masks() ? clip.tool_mask[f] : mask, clip.far));
      }
      video.push_back(frame.rgb);
    }
    if (what.on_frame) what.on_frame(f + 1, count);
  }
  nlohmann::json json;
  json["train"] = SplitMetrics(clip, what.train_frames, images, depths, calibration);
  if (!what.heldout_frames.empty()) {
    json["heldout"] = SplitMetrics(clip, what.heldout_frames, images, depths, calibration);
  }
  if (uncertain) {
    json["uncertainty_maps"] = UncertaintySettings(renderer.settings());
    if (what.write_files) maps.Write(out_dir, components, w, h, json["uncertainty_maps"]);
  }
  json["depth_png_scale"] = depth_scale;
  json["evaluation_mask"] = !clip.eval_mask.empty() ? "gt_masks" : (clip.has_masks() ? "masks" : "none");
  if (what.write_files) {
    const VideoInfo info = WriteVideo(out_dir / "video.mp4", video, w, h, 15.0);
    json["video"] = {{"path", info.path.filename().string()}, {"codec", info.codec}, {"frames", info.frames}};
  }
  return json;
}

}  // namespace endorecon::eval
