#include "worker/engine/scene/transforms_loader.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <vector>

#include "common/clip_files.h"
#include "common/error.h"
#include "common/json_file.h"
#include "worker/engine/scene/camera_json.h"
#include "worker/engine/scene/clip_checks.h"
#include "worker/engine/scene/frame_pick.h"
#include "worker/engine/scene/frame_reader.h"
#include "worker/engine/scene/transforms_clip.h"

namespace endorecon::scene {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

void WarnAboutDistortion(const json& top, const std::string& file) {
  std::string found;
  auto scan = [&found](const json& object) {
    for (const char* key : {"k1", "k2", "k3", "k4", "p1", "p2"}) {
      if (object.contains(key) && object[key].is_number() && object[key].get<double>() != 0 &&
          found.find(key) == std::string::npos) {
        found += (found.empty() ? "" : ", ") + std::string(key);
      }
    }
  };
  scan(top);
  for (const json& frame : top["frames"]) scan(frame);
  if (!found.empty()) {
    spdlog::warn("{}: lens distortion ({}) is ignored; undistort the images for best results", file, found);
  }
}

// nerfstudio's camera models other than a pinhole's (OPENCV_FISHEYE, EQUIRECTANGULAR) map pixels to
// rays another way, which the pinhole rays here would get wrong everywhere but the centre: refused
// (it was ignored without a word; found 2026-12-05). OPENCV and SIMPLE_PINHOLE are pinholes with or
// without distortion (warned of above).
void CheckCameraModel(const json& top, const std::string& file) {
  if (!top.contains("camera_model")) return;
  const json& model = top["camera_model"];
  if (!model.is_string()) FailInvalid(file + ": \"camera_model\" must be a string, found " + model.dump());
  const std::string name = model;
  for (const char* pinhole : {"OPENCV", "PINHOLE", "SIMPLE_PINHOLE", "SIMPLE_RADIAL", "RADIAL"}) {
    if (name == pinhole) return;
  }
  FailInvalid(file + ": \"camera_model\" " + name +
              " is not a pinhole camera's; undistort the images to a pinhole camera (e.g. COLMAP's "
              "image_undistorter) and give OPENCV or PINHOLE");
}

// The size named by "w"/"h" (top level or per frame), which every frame must agree on; 0x0 if none.
void DeclaredSize(const json& top, const std::string& file, std::size_t max_pixels, Clip& clip) {
  const json& frames = top["frames"];
  for (std::size_t i = 0; i < frames.size(); ++i) {
    const std::string where = file + " frame " + std::to_string(i);
    const std::optional<double> w = FrameOrTopNumber(frames[i], top, "w", where, file);
    const std::optional<double> h = FrameOrTopNumber(frames[i], top, "h", where, file);
    if (!w || !h) continue;
    if (*w < 1 || *h < 1 || *w != std::floor(*w) || *h != std::floor(*h) || *w > 1e6 || *h > 1e6) {
      FailInvalid(where + ": \"w\" and \"h\" must be positive integers, found " + std::to_string(*w) +
                  " and " + std::to_string(*h));
    }
    if (clip.width == 0) {
      clip.width = static_cast<int>(*w);
      clip.height = static_cast<int>(*h);
      CheckFrameLimit(clip.width, clip.height, max_pixels, where + ": \"w\" x \"h\"");
    } else if (clip.width != static_cast<int>(*w) || clip.height != static_cast<int>(*h)) {
      FailInvalid(where + ": size " + SizeText(static_cast<int>(*w), static_cast<int>(*h)) +
                  " differs from the clip's " + SizeText(clip.width, clip.height) +
                  " (all frames must share one size)");
    }
  }
}

}  // namespace

Clip LoadTransformsClip(const fs::path& dir, const LoadOptions& options) {
  const fs::path path = dir / "transforms.json";
  const std::string file = path.string();
  json top = ReadJsonFile(path);
  if (!options.frames.SelectsAll() && top.is_object() && top.contains("frames") && top["frames"].is_array()) {
    json picked = json::array();
    for (const int frame : PickFrames(options.frames, top["frames"].size(), dir.string()))
      picked.push_back(std::move(top["frames"][frame]));
    top["frames"] = std::move(picked);
  }
  const std::vector<FrameFiles> files = ListTransformsFrames(dir, top);
  CheckCameraModel(top, file);
  WarnAboutDistortion(top, file);

  Clip clip;
  clip.source = dir.string();
  DeclaredSize(top, file, options.max_pixels_per_frame, clip);
  FrameReadOptions read_options = FrameReadOptionsOf(options);
  read_options.tool_value = 0;
  read_options.depth_scale = OptionalNumber(top, "depth_unit_scale_factor", file).value_or(1.0);
  if (read_options.depth_scale <= 0) FailInvalid(file + ": \"depth_unit_scale_factor\" must be positive");
  ReadFrames(files, read_options, clip);

  FinishTransformsClip(top, file, clip);
  clip.is_static = clip.is_static || options.force_static;
  return clip;
}

}  // namespace endorecon::scene
