#include "worker/engine/eval/report.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <thread>

#include "common/base64.h"
#include "common/error.h"
#include "common/job_bounds.h"
#include "common/json_file.h"
#include "common/npy.h"
#include "common/prepare_flags.h"
#include "worker/engine/eval/clip_evaluator.h"
#include "worker/engine/eval/evaluation_mask.h"
#include "worker/engine/eval/exports.h"
#include "worker/engine/eval/report_page.h"
#include "worker/engine/eval/run_environment.h"
#include "worker/engine/eval/surface_grid.h"
#include "worker/engine/scene/camera_list.h"
#include "worker/engine/scene/clip_loader.h"
#include "worker/engine/scene/frame_reader.h"

namespace endorecon::eval {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using nlohmann::literals::operator""_json_pointer;

constexpr int kDisplayWidth = 480;              // wider frames are downscaled for the page
constexpr std::size_t kSurfacePoints = 600000;  // 3D grid points over all frames: ~6 MB of the page
constexpr int kJpegQuality = 88;

// What the page shows frames of: a reconstruction's clip, or a render's camera list.
struct Views {
  std::vector<scene::Camera> cameras;
  std::vector<float> times;
  const scene::Clip* clip = nullptr;  // a reconstruction's: its images and evaluation masks
  std::optional<scene::Clip> loaded;  // ... read again from the folder config.json names
};

std::string BytesBase64(const void* data, std::size_t size) {
  return Base64(std::string_view(static_cast<const char*>(data), size));
}

cv::Mat BgrOf(const std::uint8_t* rgb, int width, int height) {
  cv::Mat bgr;
  cv::cvtColor(cv::Mat(height, width, CV_8UC3, const_cast<std::uint8_t*>(rgb)), bgr, cv::COLOR_RGB2BGR);
  return bgr;
}

// `image` (BGR, or BGRA for ".png") at most kDisplayWidth wide, as a data: URI.
std::string DataUri(const cv::Mat& image, const std::string& extension, int interpolation) {
  cv::Mat shown = image;
  if (image.cols > kDisplayWidth) {
    const int height = std::max(1, int(std::lround(double(image.rows) * kDisplayWidth / image.cols)));
    cv::resize(image, shown, cv::Size(kDisplayWidth, height), 0, 0, interpolation);
  }
  const bool jpeg = extension == ".jpg";
  std::vector<std::uint8_t> bytes;
  const std::vector<int> params =
      jpeg ? std::vector<int>{cv::IMWRITE_JPEG_QUALITY, kJpegQuality} : std::vector<int>{};
  if (!cv::imencode(extension, shown, bytes, params)) {
    Fail(ErrorCode::kInternal, "report: cannot encode a " + extension + " image");
  }
  return std::string("data:") + (jpeg ? "image/jpeg" : "image/png") + ";base64," +
         BytesBase64(bytes.data(), bytes.size());
}

scene::RgbImage ReadFrameImage(const fs::path& path, const scene::Camera& camera) {
  scene::RgbImage image = scene::ReadRgbImage(path);
  if (image.width != camera.width || image.height != camera.height) {
    FailInvalid(fmt::format("{}: size {}x{} differs from its camera's {}x{}", path.string(), image.width,
                            image.height, camera.width, camera.height));
  }
  return image;
}

std::string JpegUri(const scene::RgbImage& image) {
  return DataUri(BgrOf(image.rgb.data(), image.width, image.height), ".jpg", cv::INTER_AREA);
}

// A float32 .npy map of the results (depth, uncertainty) of shape (height, width).
std::vector<float> ReadMap(const fs::path& path, int width, int height) {
  const NpyArray array = ReadNpy(path);
  if (array.shape != std::vector<std::size_t>{std::size_t(height), std::size_t(width)}) {
    FailInvalid(fmt::format("{}: expected an array of shape ({}, {})", path.string(), height, width));
  }
  return {array.data.begin(), array.data.end()};
}

bool HasDepth(float depth) { return std::isfinite(depth) && depth > 0; }

// The 1st and 99th percentiles of every frame's rendered depth (every k-th pixel of a long clip), so a
// few pixels at the far plane do not flatten the colours of the tissue.
std::array<double, 2> DepthRange(const fs::path& results_dir, const Views& views) {
  std::vector<float> samples;
  std::size_t pixels = 0;
  for (const auto& camera : views.cameras) pixels += std::size_t(camera.width) * camera.height;
  const std::size_t every = std::max<std::size_t>(1, pixels / 2000000);
  for (std::size_t f = 0; f < views.cameras.size(); ++f) {
    const auto& camera = views.cameras[f];
    const auto depth =
        ReadMap(results_dir / "depth" / FrameFileName(int(f), ".npy"), camera.width, camera.height);
    for (std::size_t p = 0; p < depth.size(); p += every) {
      if (HasDepth(depth[p])) samples.push_back(depth[p]);
    }
  }
  if (samples.empty()) return {0.0, 1.0};
  const auto at = [&](double q) {
    auto nth = samples.begin() + std::ptrdiff_t(q * double(samples.size() - 1));
    std::nth_element(samples.begin(), nth, samples.end());
    return double(*nth);
  };
  const double lo = at(0.01), hi = at(0.99);
  return {lo, hi > lo ? hi : lo + 1.0};
}

// Depth through the colour map over [lo, hi]; pixels without depth are mid-grey, as in the heat maps.
// (exports.h writes heat maps to files only; this one goes into the page.)
cv::Mat DepthImage(const std::vector<float>& depth, int width, int height, std::array<double, 2> range) {
  cv::Mat level(height, width, CV_8UC1);
  for (std::size_t p = 0; p < depth.size(); ++p) {
    const double t = HasDepth(depth[p]) ? (depth[p] - range[0]) / (range[1] - range[0]) : 0.0;
    level.data[p] = std::uint8_t(std::lround(255.0 * std::clamp(t, 0.0, 1.0)));
  }
  cv::Mat colour;
  cv::applyColorMap(level, colour, cv::COLORMAP_VIRIDIS);
  for (std::size_t p = 0; p < depth.size(); ++p) {
    if (!HasDepth(depth[p])) colour.at<cv::Vec3b>(int(p / width), int(p % width)) = cv::Vec3b(128, 128, 128);
  }
  return colour;
}

// The 256 colours of an OpenCV colour map as 768 hex digit pairs (RGB), for the page's scale bars and
// its 3D colouring, so they match the images exactly.
std::string ColormapHex(int colormap) {
  cv::Mat ramp(1, 256, CV_8UC1);
  for (int i = 0; i < 256; ++i) ramp.at<std::uint8_t>(0, i) = std::uint8_t(i);
  cv::Mat colour;
  cv::applyColorMap(ramp, colour, colormap);
  std::string hex;
  for (int i = 0; i < 256; ++i) {
    const auto bgr = colour.at<cv::Vec3b>(0, i);
    hex += fmt::format("{:02x}{:02x}{:02x}", bgr[2], bgr[1], bgr[0]);
  }
  return hex;
}

// Tool pixels as a translucent layer the page lays over every image of the frame.
std::string ToolOverlayUri(const std::vector<std::uint8_t>& mask, int width, int height) {
  cv::Mat bgra(height, width, CV_8UC4, cv::Scalar(0, 0, 0, 0));
  for (std::size_t p = 0; p < mask.size(); ++p) {
    if (mask[p] != 0) bgra.at<cv::Vec4b>(int(p / width), int(p % width)) = cv::Vec4b(255, 200, 40, 130);
  }
  return DataUri(bgra, ".png", cv::INTER_NEAREST);
}

// A frame's surface grid and the camera the page back-projects it through (formats.md, "report.html").
json SurfaceJson(const SurfaceGrid& grid, const std::vector<std::uint8_t>& model,
                 const scene::Camera& camera) {
  // Little-endian, as the page's Uint16Array reads it on the (little-endian) machines browsers run on.
  std::string depth(grid.depth.size() * 2, '\0');
  for (std::size_t i = 0; i < grid.depth.size(); ++i) {
    depth[2 * i] = char(grid.depth[i] & 0xff);
    depth[2 * i + 1] = char(grid.depth[i] >> 8);
  }
  json c2w = json::array();
  for (int r = 0; r < 3; ++r)
    c2w.push_back({camera.c2w(r, 0), camera.c2w(r, 1), camera.c2w(r, 2), camera.c2w(r, 3)});
  return {{"grid", {grid.width, grid.height}},
          {"depth_origin", grid.depth_origin},
          {"depth_step", grid.depth_step},
          {"depth", Base64(depth)},
          {"rgb", BytesBase64(grid.rgb.data(), grid.rgb.size())},
          {"uncertainty", BytesBase64(grid.uncertainty.data(), grid.uncertainty.size())},
          {"model", model.empty() ? json(nullptr) : json(BytesBase64(model.data(), model.size()))},
          {"camera",
           {{"c2w", c2w},
            {"fx", camera.fx},
            {"fy", camera.fy},
            {"cx", camera.cx},
            {"cy", camera.cy},
            {"width", camera.width},
            {"height", camera.height}}}};
}

// The heat-map scale [0, bound] a results file records, with the JSON pointers the page shows it by.
std::optional<json> HeatScale(const json& record, const std::string& pointer, const char* unit) {
  const json::json_pointer where(pointer);
  if (!record.contains(where) || !record.at(where).is_array() || record.at(where).size() != 2) return {};
  json scale = {{"colormap", "inferno"}, {"range", record.at(where)}, {"unit", unit}};
  if (pointer.rfind("/uncertainty_maps", 0) == 0) scale["pointers"] = {pointer + "/0", pointer + "/1"};
  return scale;
}

// The frames (every image as a data: URI), their 3D surfaces and the colour scales.
void AddFrames(const fs::path& results_dir, const Views& views, const json& record, const std::string& heat,
               json& data) {
  const int count = int(views.cameras.size());
  const auto& first = views.cameras.front();
  json scales = json::object();
  const auto depth_range = DepthRange(results_dir, views);
  scales["depth"] = {{"colormap", "viridis"}, {"range", depth_range}, {"unit", "clip units"}};
  auto uncertainty_scale = HeatScale(record, heat + "/uncertainty", "score");
  // The paper's score weighs the colour's variance by lambda (1e12 by default), so its values (about
  // 1e10) said nothing to a reader (found 2026-12-07). Divided by lambda they are the colour's
  // variance (RGB in [0, 1], squared) plus a negligible density term, beside the error map's RMSE.
  const json::json_pointer lambda_at(heat.substr(0, heat.rfind('/')) + "/lambda");
  if (uncertainty_scale && record.contains(lambda_at) && record.at(lambda_at).is_number() &&
      record.at(lambda_at).get<double>() >= 1) {
    (*uncertainty_scale)["factor"] = 1.0 / record.at(lambda_at).get<double>();
    (*uncertainty_scale)["unit"] = "colour variance";  // the page's note says it is score / lambda
  }
  const auto error_scale = HeatScale(record, heat + "/error", "RMSE, RGB in [0, 1]");
  const auto model_scale = HeatScale(record, heat + "/model", "unitless");
  const bool uncertainty =
      uncertainty_scale && fs::exists(results_dir / "uncertainty" / FrameFileName(0, ".png"));
  const bool error = error_scale && fs::exists(results_dir / "error" / FrameFileName(0, ".png"));
  const bool model = model_scale && fs::exists(results_dir / "uncertainty" / FrameFileName(0, "_model.png"));
  if (uncertainty) scales["uncertainty"] = *uncertainty_scale;
  if (error) scales["error"] = *error_scale;
  if (model) scales["model"] = *model_scale;
  const double bound = uncertainty ? (*uncertainty_scale)["range"][1].get<double>() : 1.0;
  const bool tool = views.clip && (views.clip->has_masks() || !views.clip->eval_mask.empty());
  const int stride = SurfaceStride(first.width, first.height, count, kSurfacePoints);

  json frames = {{"count", count},
                 {"times", views.times},
                 {"source_width", first.width},
                 {"source_height", first.height},
                 // Rendered views may differ in size: the page then does not name one for all.
                 {"sizes_vary", std::any_of(views.cameras.begin(), views.cameras.end(),
                                            [&](const scene::Camera& c) {
                                              return c.width != first.width || c.height != first.height;
                                            })},
                 {"width", std::min(first.width, kDisplayWidth)},
                 {"height", first.width > kDisplayWidth
                                ? int(std::lround(double(first.height) * kDisplayWidth / first.width))
                                : first.height}};
  json surfaces = json::array();
  for (const char* layer : {"input", "rendered", "depth", "uncertainty", "model", "error", "tool"})
    frames[layer] = json::array();
  static const std::vector<std::uint8_t> kNoMask;
  for (int f = 0; f < count; ++f) {
    const scene::Camera& camera = views.cameras[f];
    const int w = camera.width, h = camera.height;
    const auto file = [&](const char* folder, const char* extension) {
      return results_dir / folder / FrameFileName(f, extension);
    };
    const scene::RgbImage colour = ReadFrameImage(file("rgb", ".png"), camera);
    frames["rendered"].push_back(JpegUri(colour));
    if (views.clip)
      frames["input"].push_back(DataUri(BgrOf(views.clip->rgb[f].data(), w, h), ".jpg", cv::INTER_AREA));
    const auto depth = ReadMap(file("depth", ".npy"), w, h);
    frames["depth"].push_back(DataUri(DepthImage(depth, w, h, depth_range), ".jpg", cv::INTER_AREA));
    std::vector<float> total;
    std::vector<std::uint8_t> model_levels;  // the model map on the surface's grid
    if (uncertainty) {
      frames["uncertainty"].push_back(JpegUri(ReadFrameImage(file("uncertainty", ".png"), camera)));
      total = ReadMap(file("uncertainty", ".npy"), w, h);
    }
    if (model) {
      frames["model"].push_back(JpegUri(ReadFrameImage(file("uncertainty", "_model.png"), camera)));
      model_levels = SampleHeat(camera, ReadMap(file("uncertainty", "_model.npy"), w, h),
                                (*model_scale)["range"][1].get<double>(), stride);
    }
    if (error) frames["error"].push_back(JpegUri(ReadFrameImage(file("error", ".png"), camera)));
    const auto& mask = views.clip ? EvaluationMask(*views.clip, f) : kNoMask;
    if (tool) frames["tool"].push_back(ToolOverlayUri(mask, w, h));
    surfaces.push_back(SurfaceJson(SampleSurface(camera, depth, colour.rgb, total, bound, mask, stride),
                                   model_levels, camera));
  }
  for (const char* layer : {"input", "uncertainty", "model", "error", "tool"}) {
    if (frames[layer].empty()) frames[layer] = nullptr;
  }
  const Eigen::Vector3d eye = first.c2w.col(3), up = first.c2w.col(1);
  data["frames"] = std::move(frames);
  data["scales"] = std::move(scales);
  data["surface"] = {{"stride", stride},
                     {"view", {{"eye", {eye.x(), eye.y(), eye.z()}}, {"up", {up.x(), up.y(), up.z()}}}},
                     {"frames", std::move(surfaces)}};
}

// What the page says of a clip made from a recording (its recording.json, written by the worker
// runtime's recording_clip; docs/formats.md): where the frames came from, the window and sizes, and
// each frame's time in the recording. Null when the clip has none or it does not read.
// The Run table's device: "CPU, N threads" or "cuda:N (N host threads)".
std::string DeviceText(const std::string& device, unsigned threads) {
  return device == "cpu" ? fmt::format("CPU, {} threads", threads)
                         : fmt::format("{} ({} host threads)", device, threads);
}

json RecordingOf(const fs::path& clip_dir) {
  const fs::path path = clip_dir / "recording.json";
  if (!fs::exists(path)) return nullptr;
  try {
    const json record = ReadJsonFile(path);
    json shown = json::object();
    for (const char* key : {"source", "stereo", "endoscope", "frames", "recording_frames", "recorded_size",
                            "size", "fps", "times_s"}) {
      if (record.contains(key)) shown[key] = record[key];
    }
    return shown;
  } catch (const std::exception& e) {
    spdlog::warn("report: {} is not shown: {}", path.string(), e.what());
    return nullptr;
  }
}

}  // namespace

fs::path WriteReport(const fs::path& results_dir, const scene::Clip* clip) {
  json data = {{"format", "endorecon-report/1"}, {"run", DescribeRunEnvironment()}};
  data["colormaps"] = {{"inferno", ColormapHex(cv::COLORMAP_INFERNO)},
                       {"viridis", ColormapHex(cv::COLORMAP_VIRIDIS)}};
  Views views;
  json record;  // metrics.json or render.json: the file that holds the heat-map scales
  std::string heat;
  if (fs::exists(results_dir / "metrics.json")) {
    record = ReadJsonFile(results_dir / "metrics.json");
    const json config = ReadJsonFile(results_dir / "config.json");
    if (!config.contains("clip") || !config["clip"].is_string()) {
      FailInvalid((results_dir / "config.json").string() +
                  ": no \"clip\" (the clip folder) to show the input of");
    }
    const std::string clip_dir = config["clip"];
    if (clip == nullptr) {
      scene::LoadOptions load;  // transparent inputs shown on the background the run used
      if (config.contains("/train/background"_json_pointer) && config["train"]["background"] == "black")
        load.alpha_background = {0, 0, 0};
      // The bounds the run trained with (results of before 2026-12-06 had the clip's own).
      load.fit_depth_bounds = config.contains("/train/fit_depth_bounds"_json_pointer) &&
                              config["train"]["fit_depth_bounds"] == true;
      if (config.contains("frames") && config["frames"].is_string())
        load.frames = ParseFrameRange(config["frames"].get<std::string>());
      views.loaded = scene::LoadClip(clip_dir, load);
      clip = &*views.loaded;
    }
    views.clip = clip;
    views.cameras = views.clip->cameras;
    views.times = views.clip->times;
    data["kind"] = "reconstruction";
    data["title"] = config.contains("title") && config["title"].is_string()
                        ? config["title"].get<std::string>()
                        : PathName(clip_dir);
    data["clip"] = fs::absolute(clip_dir).lexically_normal().string();
    data["recording"] = RecordingOf(clip_dir);
    // A kept clip reconstructed with --frames: each frame's time in the recording is its picked
    // frame's; the page read times_s by the frame's index after the pick, a wrong time (found
    // 2026-12-07). Times already one a frame are kept as they are.
    json& recording = data["recording"];
    if (recording.is_object() && recording.contains("times_s") && recording["times_s"].is_array() &&
        recording["times_s"].size() != views.times.size() && config.contains("frames") &&
        config["frames"].is_string()) {
      try {
        const json& times = recording["times_s"];
        const auto picked = ParseFrameRange(config["frames"].get<std::string>())
                                .PickedOf(static_cast<int>(times.size()), "", "the recording's");
        json kept = json::array();
        for (const int frame : picked) kept.push_back(times[static_cast<std::size_t>(frame)]);
        if (kept.size() == views.times.size()) {
          recording["times_s"] = kept;
        } else {
          recording.erase("times_s");  // times of another clip than this one: none shown
        }
      } catch (const std::exception&) {  // a window that does not fit these times: none shown
        recording.erase("times_s");
      }
    }
    // The depth's scale: measured (depth images, or a second eye the loss reads) or only the field's
    // own, in the units the clip's near and far bounds set (a mono recording).
    data["depth_bounds"] = {clip->near, clip->far};
    data["depth_measured"] = clip->has_depth() || clip->has_stereo();
    data["run"]["device"] = DeviceText(config.value("device", "cpu"), config.value("threads", 0u));
    data["metrics"] = record;
    data["config"] = config;
    heat = "/uncertainty_maps/heatmap_scale";
  } else if (fs::exists(results_dir / "render.json")) {
    record = ReadJsonFile(results_dir / "render.json");
    for (const auto& view : scene::ReadCameraList(results_dir / "cameras.json")) {
      views.cameras.push_back(view.camera);
      views.times.push_back(view.time);
    }
    data["kind"] = "render";
    data["title"] = PathName(results_dir);
    // The device and the results rendered from, as render.json records them (since 2026-12-07).
    data["run"]["device"] = DeviceText(record.contains("device") && record["device"].is_string()
                                           ? record["device"].get<std::string>()
                                           : "cpu",
                                       std::thread::hardware_concurrency());
    if (record.contains("results") && record["results"].is_string()) data["clip"] = record["results"];
    data["render"] = record;
    heat = "/heatmap_scale";
  } else {
    FailInvalid(results_dir.string() +
                ": holds neither metrics.json (a reconstruction's results) nor render.json (rendered views)");
  }
  // A run cancelled during its evaluation left some frames' files: the page shows none (its metrics
  // have none).
  const bool cancelled = record.is_object() && record.value("cancelled", false);
  if (!cancelled && !views.cameras.empty() && fs::exists(results_dir / "rgb" / FrameFileName(0, ".png"))) {
    AddFrames(results_dir, views, record, heat, data);
  }

  const fs::path path = results_dir / "report.html";
  const fs::path partial = results_dir / "report.html.part";
  const std::string page = FillReportPage(data);
  {
    std::ofstream out(partial, std::ios::binary | std::ios::trunc);
    out.write(page.data(), std::streamsize(page.size()));
    if (!out) Fail(ErrorCode::kUnavailable, "cannot write " + partial.string());
  }
  std::error_code failed;
  fs::rename(partial, path, failed);
  if (failed) Fail(ErrorCode::kUnavailable, "cannot rename " + partial.string() + ": " + failed.message());
  spdlog::info("report: {} ({:.1f} MB)", path.string(), double(page.size()) / 1e6);
  return path;
}

}  // namespace endorecon::eval
