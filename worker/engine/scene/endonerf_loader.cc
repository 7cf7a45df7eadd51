#include "worker/engine/scene/endonerf_loader.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>

#include "common/clip_files.h"
#include "common/error.h"
#include "common/json_file.h"
#include "common/pose_rows.h"
#include "worker/engine/scene/clip_checks.h"
#include "worker/engine/scene/frame_pick.h"
#include "worker/engine/scene/frame_reader.h"

namespace endorecon::scene {
namespace {

namespace fs = std::filesystem;

// The cameras of poses_bounds.npy's rows (common/pose_rows.h, which checks them), at the size the
// file gives; MatchImageSize adapts them to the images'.
std::vector<Camera> CamerasOf(const PoseRows& poses) {
  std::vector<Camera> cameras;
  cameras.reserve(poses.rows.size());
  for (const PoseRow& row : poses.rows) {
    Camera camera;
    camera.width = row.width;
    camera.height = row.height;
    camera.fx = camera.fy = row.focal;
    camera.cx = row.width / 2.0;
    camera.cy = row.height / 2.0;
    std::copy(row.c2w, row.c2w + 12, camera.c2w.data());
    cameras.push_back(camera);
  }
  return cameras;
}

double ReadBaseline(const fs::path& dir) {
  const fs::path path = dir / "stereo.json";
  if (!fs::exists(path)) {
    spdlog::warn("{}: images_right/ without stereo.json; assuming a baseline of {} clip units", dir.string(),
                 kDefaultStereoBaseline);
    return kDefaultStereoBaseline;
  }
  const nlohmann::json json = ReadJsonFile(path);
  if (!json.is_object() || !json.contains("baseline") || !json["baseline"].is_number() ||
      !std::isfinite(json["baseline"].get<double>()) || json["baseline"].get<double>() <= 0) {
    FailInvalid(path.string() + ": expected {\"baseline\": b} with a finite b > 0, found " + json.dump());
  }
  return json["baseline"].get<double>();
}

// Adapts f and the principal point to images stored at a uniform fraction of the pose file's size.
void MatchImageSize(const fs::path& first_image, int width, int height, std::vector<Camera>& cameras) {
  const Camera& c0 = cameras.front();
  if (width == c0.width && height == c0.height) return;
  const double scale = static_cast<double>(width) / c0.width;
  if (std::abs(c0.height * scale - height) > 0.5 + 1e-9) {
    FailInvalid(first_image.string() + ": size " + SizeText(width, height) +
                " does not match poses_bounds.npy's " + SizeText(c0.width, c0.height) +
                " (nor a uniform scaling of it)");
  }
  spdlog::info("{}: images are {} while poses_bounds.npy says {}; scaling the focal length by {}",
               first_image.parent_path().string(), SizeText(width, height), SizeText(c0.width, c0.height),
               scale);
  for (Camera& camera : cameras) {
    camera.fx *= scale;
    camera.fy *= scale;
    camera.width = width;
    camera.height = height;
    camera.cx = width / 2.0;
    camera.cy = height / 2.0;
  }
}

}  // namespace

Clip LoadEndoNerfClip(const fs::path& dir, const LoadOptions& options) {
  const PoseRows poses = ReadPoseRows(dir / "poses_bounds.npy");
  std::vector<Camera> cameras = CamerasOf(poses);
  std::vector<FrameFiles> frames = ListEndoNerfFrames(dir, cameras.size());
  if (!options.frames.SelectsAll()) {
    const std::vector<int> picked = PickFrames(options.frames, frames.size(), dir.string());
    KeepPicked(picked, frames);
    KeepPicked(picked, cameras);
  }
  const std::size_t n = cameras.size();

  Clip clip;
  clip.source = dir.string();
  ReadFrames(frames, FrameReadOptionsOf(options), clip);
  MatchImageSize(frames[0].image, clip.width, clip.height, cameras);

  clip.cameras = std::move(cameras);
  clip.near = poses.near;
  clip.far = poses.far;
  clip.times.resize(n);
  for (std::size_t i = 0; i < n; ++i)
    clip.times[i] = n == 1 ? 0.f : static_cast<float>(i) / static_cast<float>(n - 1);

  if (clip.has_stereo()) {
    const double baseline = ReadBaseline(dir);
    clip.right_cameras = clip.cameras;
    for (Camera& camera : clip.right_cameras) camera.c2w.col(3) += baseline * camera.c2w.col(0);
  } else if (fs::exists(dir / "stereo.json")) {
    spdlog::warn("{}: stereo.json without images_right/: the clip is trained on its left eye alone",
                 dir.string());
  }
  clip.is_static = options.force_static || n == 1;
  return clip;
}

}  // namespace endorecon::scene
