#include "worker/engine/eval/clip_evaluator.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <future>
#include <limits>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <span>
#include <string>
#include <utility>

#include "common/error.h"
#include "common/npy.h"
#include "worker/engine/base/seconds_since.h"
#include "worker/engine/eval/calibration.h"
#include "worker/engine/eval/depth_error.h"
#include "worker/engine/eval/evaluation_mask.h"
#include "worker/engine/eval/exports.h"
#include "worker/engine/eval/gain_fit.h"
#include "worker/engine/eval/image_metrics.h"
#include "worker/engine/eval/model_uncertainty.h"
#include "worker/engine/eval/neighbour_evidence.h"
#include "worker/engine/eval/pixel_error.h"
#include "worker/engine/eval/point_cloud.h"
#include "worker/engine/eval/strided_map.h"
#include "worker/engine/eval/summary.h"
#include "worker/engine/eval/surface_mesh.h"
#include "worker/engine/eval/video_writer.h"
#include "worker/engine/eval/warnings.h"
#include "worker/engine/scene/outside_view.h"

namespace endorecon::eval {

namespace {

bool Contains(const std::vector<int>& frames, int f) {
  return std::find(frames.begin(), frames.end(), f) != frames.end();
}

// Per frame, one map's calibration against the observed image (metrics.json's `key`) and against
// the noise-free truth (`key`_noise_free); empty where not measured.
struct MapCalibration {
  std::string key;
  std::vector<Calibration> observed, noise_free;
};

// Image metrics per frame against one reference: the observed images or, where the clip has it, the
// noise-free truth; as rendered, or (held-out frames) after the frame's exposure is fitted
// (gain_fit.h). `frames` is empty where not measured.
struct ImageGroup {
  const char* key;  // metrics.json's key in each split
  bool noise_free, gain_fitted;
  std::vector<ImageMetrics> frames;
};

constexpr const char* kAgainstNoiseFree = "gt/images: the noise-free tissue (tool pixels left out)";
constexpr const char* kGainFitted =
    "the render times one gain per colour channel fitted to the frame over its tissue (least squares), as "
    "NeRF-W fits a test image's appearance: a held-out time's exposure cannot be predicted";

nlohmann::json SplitMetrics(const scene::Clip& clip, const std::vector<int>& frames, bool heldout,
                            const std::vector<ImageGroup>& images, const std::vector<DepthError>& depths,
                            const std::vector<MapCalibration>& calibrations) {
  std::vector<DepthError> depth_subset;
  for (int f : frames) {
    if (!depths.empty()) depth_subset.push_back(depths[f]);
  }
  nlohmann::json json;
  json["frames"] = frames;
  for (const ImageGroup& group : images) {
    if (group.frames.empty() || (group.gain_fitted && !heldout)) continue;
    std::vector<ImageMetrics> subset;
    for (int f : frames) subset.push_back(group.frames[f]);
    auto& image = json[group.key] = ToJson(std::span<const ImageMetrics>(subset));
    if (group.noise_free) image["against"] = kAgainstNoiseFree;
    if (group.gain_fitted) image["exposure"] = kGainFitted;
  }
  if (!clip.gt_depth.empty()) json["depth"] = ToJson(std::span<const DepthError>(depth_subset));
  const auto subset = [&](const std::vector<Calibration>& all) {
    std::vector<Calibration> part;
    for (int f : frames) part.push_back(all[f]);
    return ToJson(std::span<const Calibration>(part));
  };
  for (const auto& map : calibrations) {
    if (!map.observed.empty()) json[map.key] = subset(map.observed);
    if (map.noise_free.empty()) continue;
    auto& noise_free = json[map.key + "_noise_free"] = subset(map.noise_free);
    noise_free["error_against"] = kAgainstNoiseFree;
  }
  return json;
}

// The uncertainty maps go to disk frame by frame (their .npy files; the error maps into a scratch
// folder), and only a sample of their values stays for the heat maps' scale, one per clip: the
// heat-map PNGs are drawn from the files once the last frame is rendered. Keeping every frame's maps
// in memory instead cost 20 bytes a pixel of the clip (40 GB for 600 frames of 1920 x 1080).
struct UncertaintyMaps {
  std::filesystem::path dir, error_dir, scratch;
  HeatmapScale total, error, model;

  UncertaintyMaps(const std::filesystem::path& out_dir, std::size_t values_in_all)
      : dir(out_dir / "uncertainty"),
        error_dir(out_dir / "error"),
        scratch(out_dir / ".error-maps"),
        total(values_in_all),
        error(values_in_all),
        model(values_in_all) {
    for (const auto& sub : {dir, error_dir, scratch}) std::filesystem::create_directories(sub);
  }

  // Frame f's paper's map, its components and its error map (on the writer thread).
  void WriteFrame(int f, const render::RenderedFrame& maps, const std::vector<float>& error_map, int w,
                  int h) const {
    WriteDepthNpy(dir / FrameFileName(f, ".npy"), maps.uncertainty, w, h);
    WriteDepthNpy(dir / FrameFileName(f, "_aleatoric.npy"), maps.aleatoric, w, h);
    WriteDepthNpy(dir / FrameFileName(f, "_epistemic.npy"), maps.epistemic, w, h);
    WriteDepthNpy(scratch / FrameFileName(f, ".npy"), error_map, w, h);
  }

  // The heat maps of `count` frames from their files, on every core, then the scratch folder goes.
  void WriteHeatmaps(int count, int w, int h, nlohmann::json& json) const {
    // The error map's top is at least an 8-bit step: a perfect render's float noise (5e-7 on an
    // all-white clip) drew a bright map of nothing (found 2026-12-06).
    const double total_bound = total.UpperBound(), error_bound = std::max(error.UpperBound(), 1.0 / 255),
                 model_bound = model.UpperBound();
    const auto read = [](const std::filesystem::path& path) {
      const NpyArray array = ReadNpy(path);
      return std::vector<float>(array.data.begin(), array.data.end());
    };
    tbb::parallel_for(0, count, [&](int f) {
      WriteHeatmapPng(dir / FrameFileName(f, ".png"), read(dir / FrameFileName(f, ".npy")), w, h, 0.0,
                      total_bound);
      WriteHeatmapPng(dir / FrameFileName(f, "_model.png"), read(dir / FrameFileName(f, "_model.npy")), w, h,
                      0.0, model_bound);
      WriteHeatmapPng(error_dir / FrameFileName(f, ".png"), read(scratch / FrameFileName(f, ".npy")), w, h,
                      0.0, error_bound);
    });
    std::error_code ignored;
    std::filesystem::remove_all(scratch, ignored);
    json["heatmap_scale"] = {
        {"uncertainty", {0.0, total_bound}}, {"error", {0.0, error_bound}}, {"model", {0.0, model_bound}}};
    // Where the bound came from: every value, or every k-th of a large clip's.
    if (total.stride() > 1) json["heatmap_scale"]["sampled_every"] = total.stride();
  }
};

using Clock = std::chrono::steady_clock;

using base::SecondsSince;

// A frame rendered as the plan says: full, or reduced (colour and depth from `plain`, the uncertainty
// maps from the dropout passes on a strided grid, upsampled). A reduced frame's calibration is
// measured where the uncertainty was estimated: on the grid, against the error of the dropout
// passes' mean colour there (what the uncertainty describes), not against the cheaper render's error
// through interpolated values.
struct EvaluatedFrame {
  render::RenderedFrame frame;
  // Reduced frames with uncertainty: the grid's pixels, the passes' mean colour and the maps there.
  std::vector<int> grid;
  std::vector<float> grid_rgb, grid_total, grid_aleatoric, grid_epistemic;
};

// Outside the scope's view every map holds 0, as the rendered colour and depth do
// (docs/formats.md): a reduced frame's maps, upsampled from a grid rendered everywhere, and the model
// map's neighbour terms reached into it (found 2026-12-05).
void ZeroOutsideView(const scene::Clip& clip, std::vector<float>& map) {
  if (clip.outside_view.size() != map.size()) return;
  for (std::size_t i = 0; i < map.size(); ++i) {
    if (clip.outside_view[i]) map[i] = 0;
  }
}

EvaluatedFrame RenderFrame(const scene::Clip& clip, int f, FrameRender how, int stride,
                           render::FrameRenderer& full, render::FrameRenderer* plain) {
  const scene::Camera& camera = clip.cameras[f];
  // Outside the scope's view is neither trained nor scored: left black, unrendered.
  if (how == FrameRender::kFull)
    return {full.Render(camera, clip.times[f], clip.outside_view), {}, {}, {}, {}, {}};
  EvaluatedFrame out{plain->Render(camera, clip.times[f], clip.outside_view), {}, {}, {}, {}, {}};
  if (full.settings().mc_passes == 0) return out;
  out.grid = StridedPixels(camera.width, camera.height, stride);
  const int n = int(out.grid.size());
  out.grid_rgb.resize(3 * std::size_t(n));
  out.grid_total.resize(n);
  out.grid_aleatoric.resize(n);
  out.grid_epistemic.resize(n);
  std::vector<float> depth(n), opacity(n);
  full.RenderPixels(camera, clip.times[f], out.grid.data(), n,
                    {out.grid_rgb.data(), depth.data(), opacity.data(), out.grid_total.data(),
                     out.grid_aleatoric.data(), out.grid_epistemic.data()});
  render::RenderedFrame& frame = out.frame;
  frame.uncertainty = UpsampleStrided(out.grid_total, camera.width, camera.height, stride);
  frame.aleatoric = UpsampleStrided(out.grid_aleatoric, camera.width, camera.height, stride);
  frame.epistemic = UpsampleStrided(out.grid_epistemic, camera.width, camera.height, stride);
  for (auto* map : {&frame.uncertainty, &frame.aleatoric, &frame.epistemic}) ZeroOutsideView(clip, *map);
  return out;
}

// A frame's model map (model_uncertainty.h) and what its calibration needs, kept until the
// kNeighbourFrames frames after it are rendered and their evidence (neighbour_evidence.h) can be added: the
// map over the whole frame (written) and on a reduced frame's grid, and per reference (the observed image,
// the noise-free truth where known) the per-pixel error calibration measures it against.
struct PendingModelMap {
  std::vector<float> map, grid_map;
  std::vector<int> grid;
  std::vector<float> rgb;    // the frame's rendered colours: their brightness bins the evidence
  std::vector<float> depth;  // the frame's rendered depth: where its pixels sit in the neighbours
  std::vector<float> error_observed, error_noise_free;  // over the whole frame, or on the grid
};

// A frame's calibration errors against a reference image (the clip's, or its noise-free truth): a
// full frame's per-pixel error (`error`, when given, already computed), or on a reduced frame's grid
// the error of the dropout passes' mean colour there.
std::vector<float> CalibrationError(const EvaluatedFrame& evaluated, std::span<const std::uint8_t> reference,
                                    int w, int h, std::span<const float> error = {}) {
  if (evaluated.grid.empty()) {
    if (!error.empty()) return {error.begin(), error.end()};
    return PixelRmse(evaluated.frame.rgb, reference, w, h);
  }
  const int n = int(evaluated.grid.size());
  return PixelRmse(evaluated.grid_rgb, Gather(reference, evaluated.grid, 3), n, 1);
}

// A frame's calibration of a map (`map` over the whole frame, `grid_map` on a reduced frame's grid)
// against the errors CalibrationError gives.
Calibration FrameCalibration(std::span<const float> map, std::span<const float> grid_map,
                             const std::vector<int>& grid, std::span<const float> error,
                             const std::vector<std::uint8_t>& mask) {
  if (grid.empty())
    return MeasureCalibration(map, error, mask, kSparsificationSteps, kEightBitErrorResolution);
  return MeasureCalibration(grid_map, error, Gather<std::uint8_t>(mask, grid), kSparsificationSteps,
                            kEightBitErrorResolution);
}

PendingModelMap ModelMap(const EvaluatedFrame& evaluated, const std::vector<std::uint8_t>& mask) {
  const auto& frame = evaluated.frame;
  PendingModelMap pending;
  pending.map = ModelUncertainty(frame.rgb, frame.aleatoric, frame.epistemic, mask);
  if (!evaluated.grid.empty()) {
    pending.grid = evaluated.grid;
    pending.grid_map = ModelUncertainty(evaluated.grid_rgb, evaluated.grid_aleatoric,
                                        evaluated.grid_epistemic, Gather<std::uint8_t>(mask, evaluated.grid));
  }
  pending.rgb = frame.rgb;
  pending.depth = frame.depth;
  return pending;
}

}  // namespace

nlohmann::json UncertaintySettings(const render::FrameRenderSettings& settings) {
  return {
      {"mc_passes", settings.mc_passes},
      {"lambda", settings.color_weight},
      {"variance_eps", settings.variance_eps},
      {"error_measure", "per-pixel RMSE over the RGB channels, colours in [0, 1] (eval::PixelRmse)"},
      {"score", "S_ray = sum_j w_j (var_sigma,j + lambda var_c,j) / sum_j w_j, raw variances"},
      {"model_map",
       "aleatoric score / the frame's median aleatoric score at the pixel's rendered brightness, plus the "
       "epistemic score, each relative to its mean over the frame's tissue (eval/model_uncertainty.h); in a "
       "clip's evaluation plus 0.4 times the neighbouring training frames' (within 4 frames, weights "
       "1/distance) signed residuals at the pixel the surface projects to, averaged, squared, relative to "
       "its median at the frame's brightness and to its tissue mean, plus 0.4 times the render's "
       "disagreement with the training frames' images within 2 frames (weights 1/distance, their tools "
       "left out), averaged, blurred (Gaussian, sigma 1 pixel), squared, relative to its tissue mean "
       "(eval/neighbour_evidence.h)"}};
}

nlohmann::json EvaluateClip(const scene::Clip& clip, render::FrameRenderer& renderer,
                            const ClipEvaluation& what, const std::filesystem::path& out_dir) {
  const auto wall = Clock::now();
  // A stop is heeded within a frame too, between its chunks; the renderers' stop is theirs again after.
  struct HeededStop {
    std::vector<render::FrameRenderer*> renderers;
    ~HeededStop() {
      for (auto* r : renderers) r->SetStop({});
    }
  } heeded;
  if (what.should_stop) {
    for (auto* r : {&renderer, what.plain}) {
      if (r == nullptr) continue;
      r->SetStop(what.should_stop);
      heeded.renderers.push_back(r);
    }
  }
  const int count = clip.frame_count();
  const int w = clip.width, h = clip.height;
  const double depth_scale = DepthPngScale(clip.far);
  if (what.write_files) {
    for (const char* sub : {"rgb", "depth", "pointcloud"}) std::filesystem::create_directories(out_dir / sub);
  }
  std::vector<ImageGroup> images;
  for (const bool noise_free : {false, true}) {
    for (const bool gain_fitted : {false, true}) {
      const char* key = noise_free ? (gain_fitted ? "image_noise_free_gain_fitted" : "image_noise_free")
                                   : (gain_fitted ? "image_gain_fitted" : "image");
      const bool measured = !noise_free || !clip.gt_rgb.empty();
      images.push_back({key, noise_free, gain_fitted, std::vector<ImageMetrics>(measured ? count : 0)});
    }
  }
  std::vector<DepthError> depths(clip.gt_depth.empty() ? 0 : count);
  // The video is written as the frames are (one frame's files in flight at a time, in order).
  std::unique_ptr<VideoWriter> video;
  if (what.write_files) video = std::make_unique<VideoWriter>(out_dir / "video.mp4", w, h, 15.0);
  const bool uncertain = renderer.settings().mc_passes > 0;
  const std::size_t calibrated = uncertain ? count : 0,
                    with_truth = uncertain && !clip.gt_rgb.empty() ? count : 0;
  // The paper's map and the model map, each against the observed image and the noise-free truth.
  std::vector<MapCalibration> calibrations;
  for (const char* key : {"calibration", "calibration_model_map"}) {
    calibrations.push_back({key, std::vector<Calibration>(calibrated), std::vector<Calibration>(with_truth)});
  }
  std::optional<UncertaintyMaps> maps;
  if (uncertain && what.write_files)
    maps.emplace(out_dir, std::size_t(count) * std::size_t(w) * std::size_t(h));
  std::vector<PendingModelMap> model_maps(calibrated);
  std::vector<std::vector<float>> evidence(calibrated);  // the training frames' (neighbour_evidence.h)
  std::vector<NeighbourImage> neighbour_images(calibrated);  // the training frames' images, with their tools
  for (int f : what.train_frames) {
    if (f < 0 || std::size_t(f) >= neighbour_images.size()) continue;
    neighbour_images[f] = {clip.rgb[f], clip.has_masks() ? clip.tool_mask[f] : EvaluationMask(clip, f)};
  }
  const int rendered_pixels = RenderedPixels(clip);  // a frame's price (a count over the mask: once)
  FramePacer pacer(what.plan, what.heldout_frames, rendered_pixels, what.plain != nullptr,
                   what.heldout_slack_s);
  std::future<double> writing;  // the previous frame's files; returns the seconds they took
  bool mesh_empty = false;      // set by frame 0's writing, read once it is done
  double render_seconds = 0, write_seconds = 0, model_map_seconds = 0;
  double render_priced = 0;  // what the frames as rendered cost at the plan's measured prices
  std::vector<int> full_frames, reduced_frames;
  nlohmann::json coarser = nlohmann::json::array();  // reduced frames given a coarser stride than planned
  // Finishes frame f's model map once the frames within kNeighbourFrames after it are rendered: adds
  // their evidence, calibrates the map, keeps it to write, and lets go of what no later frame needs.
  const auto finish_model_map = [&](int f) {
    const auto start = Clock::now();
    PendingModelMap& model = model_maps[f];
    const auto& mask = EvaluationMask(clip, f);
    const std::vector<float> residuals =
        NeighbourEvidence(clip.cameras, f, model.rgb, model.depth, mask, evidence);
    const std::vector<float> disagreement =
        NeighbourDisagreement(clip.cameras, f, model.rgb, model.depth, neighbour_images);
    for (const auto& [term, weight] : {std::pair{&residuals, kNeighbourEvidenceWeight},
                                       std::pair{&disagreement, kNeighbourDisagreementWeight}}) {
      AddNeighbourTerm(model.map, *term, weight, mask);
      if (!model.grid.empty()) {
        AddNeighbourTerm(model.grid_map, Gather<float>(*term, model.grid), weight,
                         Gather<std::uint8_t>(mask, model.grid));
      }
    }
    calibrations[1].observed[f] =
        FrameCalibration(model.map, model.grid_map, model.grid, model.error_observed, mask);
    if (!model.error_noise_free.empty()) {
      calibrations[1].noise_free[f] =
          FrameCalibration(model.map, model.grid_map, model.grid, model.error_noise_free, mask);
    }
    ZeroOutsideView(clip, model.map);
    if (maps) {
      maps->model.Add(model.map, mask);
      WriteDepthNpy(maps->dir / FrameFileName(f, "_model.npy"), model.map, w, h);
    }
    model = {};
    if (f >= kNeighbourFrames) evidence[f - kNeighbourFrames] = {};  // the next frame looks no further back
    model_map_seconds += SecondsSince(start);
  };
  for (int f = 0; f < count; ++f) {
    // A cancel or a shutdown is heeded between frames: rendering every frame of a large clip took
    // minutes after a cancel, the worker busy and its next job waiting (found 2026-12-07).
    if (what.should_stop && what.should_stop()) {
      if (writing.valid()) writing.get();
      Fail(ErrorCode::kCancelled,
           fmt::format("stopped during evaluation, {} of {} frames rendered", f, count));
    }
    const auto start = Clock::now();
    const FrameChoice choice =
        pacer.Choose(f, what.deadline == Clock::time_point::max()
                            ? std::numeric_limits<double>::infinity()
                            : std::chrono::duration<double>(what.deadline - start).count());
    const FrameRender how =
        what.plain != nullptr ? choice.how : FrameRender::kFull;  // (nothing to reduce with)
    EvaluatedFrame evaluated;
    try {
      evaluated = RenderFrame(clip, f, how, choice.stride, renderer, what.plain);
    } catch (const Error& e) {
      if (e.code() != ErrorCode::kCancelled) throw;
      if (writing.valid()) writing.get();  // the previous frame's files, whose task reads these locals
      Fail(ErrorCode::kCancelled,
           fmt::format("stopped during evaluation, in frame {} ({} of {} frames rendered)", f, f, count));
    }
    render::RenderedFrame& frame = evaluated.frame;
    render_seconds += SecondsSince(start);
    render_priced += FrameSeconds(how, choice.stride, what.plan.cost, rendered_pixels);
    (how == FrameRender::kFull ? full_frames : reduced_frames).push_back(f);
    if (how == FrameRender::kReduced && choice.stride != what.plan.stride) {
      coarser.push_back({{"frame", f}, {"stride", choice.stride}});
    }
    const auto& mask = EvaluationMask(clip, f);
    const bool heldout = Contains(what.heldout_frames, f);
    for (ImageGroup& group : images) {
      if (group.frames.empty() || (group.gain_fitted && !heldout)) continue;
      const auto& reference = group.noise_free ? clip.gt_rgb[f] : clip.rgb[f];
      group.frames[f] =
          MeasureImage(group.gain_fitted ? FitGain(frame.rgb, reference, mask, w, h).rgb : frame.rgb,
                       reference, mask, w, h);
    }
    render::RenderedFrame frame_maps;  // the paper's map and its components, to write
    std::vector<float> error_map;
    if (uncertain) {
      std::vector<float> error = PixelRmse(frame.rgb, clip.rgb[f], w, h);
      // The paper's map now; the model map once its neighbours are rendered (finish_model_map).
      PendingModelMap& model = model_maps[f] = ModelMap(evaluated, mask);
      model.error_observed = CalibrationError(evaluated, clip.rgb[f], w, h, error);
      calibrations[0].observed[f] = FrameCalibration(frame.uncertainty, evaluated.grid_total, evaluated.grid,
                                                     model.error_observed, mask);
      if (!clip.gt_rgb.empty()) {
        model.error_noise_free = CalibrationError(evaluated, clip.gt_rgb[f], w, h);
        calibrations[0].noise_free[f] = FrameCalibration(frame.uncertainty, evaluated.grid_total,
                                                         evaluated.grid, model.error_noise_free, mask);
      }
      if (Contains(what.train_frames, f))
        evidence[f] = ResidualEvidence(frame.rgb, clip.rgb[f], neighbour_images[f].tool_mask);
      if (f >= kNeighbourFrames) finish_model_map(f - kNeighbourFrames);
      if (maps) {
        maps->total.Add(frame.uncertainty, mask);
        maps->error.Add(error, mask);
        frame_maps.uncertainty = std::move(frame.uncertainty);
        frame_maps.aleatoric = std::move(frame.aleatoric);
        frame_maps.epistemic = std::move(frame.epistemic);
        error_map = std::move(error);
      }
    }
    if (!depths.empty())
      depths[f] = MeasureDepth(frame.depth, clip.gt_depth[f], mask, w, h, clip.near, clip.far);
    if (what.write_files) {
      ClearDepthWithoutSurface(frame.depth, frame.opacity);  // after the depth metrics
      if (writing.valid()) write_seconds += writing.get();  // one frame's files in flight at a time
      const auto& cloud_mask = clip.has_masks() ? clip.tool_mask[f] : mask;
      writing = std::async(
          std::launch::async, [&clip, &out_dir, &cloud_mask, &maps, &mesh_empty, video = video.get(), f, w, h,
                               depth_scale, rgb = std::move(frame.rgb), depth = std::move(frame.depth),
                               frame_maps = std::move(frame_maps), error_map = std::move(error_map)] {
            const auto start = Clock::now();
            video->Write(rgb);
            if (maps) maps->WriteFrame(f, frame_maps, error_map, w, h);
            WritePng8(out_dir / "rgb" / FrameFileName(f, ".png"), rgb, w, h);
            WriteDepthNpy(out_dir / "depth" / FrameFileName(f, ".npy"), depth, w, h);
            WriteDepthPng16(out_dir / "depth" / FrameFileName(f, ".png"), depth, w, h, depth_scale);
            WritePly(out_dir / "pointcloud" / FrameFileName(f, ".ply"),
                     BackProject(clip.cameras[f], depth, rgb, cloud_mask));
            if (f == 0) {  // the canonical frame's surface (t = 0)
              const SurfaceMesh mesh = TriangulateDepth(clip.cameras[f], depth, rgb, cloud_mask, clip.far);
              mesh_empty = mesh.triangle_count() == 0;  // said, not only written empty (found 2026-12-07)
              WriteSurfaceMesh(out_dir, mesh);
            }
            return SecondsSince(start);
          });
    }
    // The pace counts the frame's whole time: on large frames its measures (SSIM, calibration), model
    // map and the wait for the previous frame's files cost a good part of its render's.
    pacer.Rendered(choice, SecondsSince(start));
    if (what.on_frame) what.on_frame(f + 1, count);
  }
  if (writing.valid()) write_seconds += writing.get();
  if (uncertain) {
    for (int f = std::max(0, count - kNeighbourFrames); f < count; ++f) finish_model_map(f);
  }
  nlohmann::json json;
  if (mesh_empty) {
    Warn(json,
         "the canonical frame (frame 0) shows no tissue surface (all tool, or nothing rendered short of the "
         "far bound): mesh.ply, mesh.obj and mesh.stl hold no triangle");
  }
  json["train"] = SplitMetrics(clip, what.train_frames, false, images, depths, calibrations);
  if (!what.heldout_frames.empty()) {
    json["heldout"] = SplitMetrics(clip, what.heldout_frames, true, images, depths, calibrations);
  }
  const auto tail = Clock::now();
  if (uncertain) {
    json["uncertainty_maps"] = UncertaintySettings(renderer.settings());
    if (maps) maps->WriteHeatmaps(count, w, h, json["uncertainty_maps"]);
  }
  json["depth_png_scale"] = depth_scale;
  json["evaluation_mask"] = !clip.eval_mask.empty() ? "gt_masks" : (clip.has_masks() ? "masks" : "none");
  if (what.write_files) {
    video->Close();
    json["video"] = {{"path", video->path().filename().string()},
                     {"codec", video->codec()},
                     {"frames", video->frames_written()}};
  }
  write_seconds += SecondsSince(tail);
  nlohmann::json& how = json["evaluation"];
  how["full_frames"] = full_frames;
  const auto& full = renderer.settings();
  how["full"] = uncertain ? fmt::format(
                                "{} dropout passes at every pixel ({} + {} samples per ray): colour "
                                "and depth from their mean",
                                full.mc_passes, full.coarse_samples, full.fine_samples)
                          : "one pass at every pixel";
  if (!reduced_frames.empty()) {
    how["reduced_frames"] = reduced_frames;
    if (uncertain) how["uncertainty_stride"] = what.plan.stride;  // no maps, no stride (mc_passes 0)
    // Held-out frames reduced when the run's budget could not afford them full: their scores are the
    // reduced render's.
    nlohmann::json heldout_reduced = nlohmann::json::array();
    for (int f : reduced_frames) {
      if (Contains(what.heldout_frames, f)) heldout_reduced.push_back(f);
    }
    if (!heldout_reduced.empty()) how["heldout_reduced"] = heldout_reduced;
    // Frames whose maps took a coarser stride to keep the deadline (the plan's prices were low).
    if (uncertain && !coarser.empty()) how["uncertainty_stride_late"] = coarser;
    const auto& plain = what.plain->settings();
    how["reduced"] =
        uncertain ? fmt::format(
                        "colour and depth from one dropout-off pass at every pixel ({0} + {1} samples per "
                        "ray); uncertainty from the dropout passes on a grid of one pixel in {2} of one row "
                        "in {2}, bilinearly upsampled; their calibration on that grid, against the error "
                        "of the dropout passes' mean colour there",
                        plain.coarse_samples, plain.fine_samples, what.plan.stride)
                  : fmt::format(
                        "colour and depth from one pass at every pixel with fewer samples ({} + {} per ray)",
                        plain.coarse_samples, plain.fine_samples);
  }
  how["seconds"] = {{"render", render_seconds},
                    {"model_maps", model_map_seconds},
                    {"write", write_seconds},
                    {"wall", SecondsSince(wall)}};
  // What the plan predicted the rendering would take (absent when its costs were not measured).
  // What the frames as rendered would have taken at those prices: rendering over it is the pace the
  // prices missed by (a few tenths of a second of rendering on a loaded machine priced 2.3x high).
  if (what.plan.cost.known()) {
    how["seconds"]["render_planned"] = what.plan.seconds;
    how["seconds"]["render_priced"] = render_priced;
  }
  // The training split's tissue PSNR by how its frames were rendered: a reduced frame's colour is a
  // cheaper render's, so the split's summary mixes two renders; the full frames' is the one to
  // compare across runs. Against the observed images, and against the noise-free truth where known.
  if (!reduced_frames.empty()) {
    for (const ImageGroup& group : images) {
      if (group.gain_fitted || group.frames.empty()) continue;
      const std::string key = group.noise_free ? "train_psnr_tissue_noise_free" : "train_psnr_tissue";
      for (const auto& [name, frames] :
           {std::pair{"full", &full_frames}, std::pair{"reduced", &reduced_frames}}) {
        std::vector<double> psnr;
        for (int f : *frames) {
          if (Contains(what.train_frames, f)) psnr.push_back(group.frames[f].psnr_tissue);
        }
        const Summary summary = Summarise(psnr);
        if (summary.count > 0) how[key][name] = ToJson(summary);  // no NaN for none
      }
    }
    // The depth the same way: a reduced frame's is one plain pass's, a little worse than the full
    // frames' (its mean was read as a regression against a run of all-full frames; found 2026-12-06).
    if (!depths.empty()) {
      for (const auto& [name, frames] :
           {std::pair{"full", &full_frames}, std::pair{"reduced", &reduced_frames}}) {
        std::vector<double> rmse;
        for (int f : *frames) {
          if (Contains(what.train_frames, f)) rmse.push_back(depths[f].rmse);
        }
        const Summary summary = Summarise(rmse);
        if (summary.count > 0) how["train_depth_rmse"][name] = ToJson(summary);
      }
    }
  }
  return json;
}

}  // namespace endorecon::eval
