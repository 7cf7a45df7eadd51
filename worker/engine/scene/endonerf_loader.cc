#include "worker/engine/scene/endonerf_loader.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>

#include "common/clip_files.h"
#include "common/error.h"
#include "common/json_file.h"
#include "common/npy.h"
#include "worker/engine/scene/clip_checks.h"
#include "worker/engine/scene/frame_pick.h"
#include "worker/engine/scene/frame_reader.h"

namespace endorecon::scene {
namespace {

namespace fs = std::filesystem;

struct PoseRows {
  std::vector<Camera> cameras;  // width/height/f from the file; cx, cy set later
  double near = 0, far = 0;
};

std::string Number(double value) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.9g", value);
  return text;
}

PoseRows ReadPoseRows(const fs::path& path) {
  if (!fs::exists(path)) FailInvalid(path.string() + ": file does not exist");
  const NpyArray array = ReadNpy(path);
  const std::size_t rows = PoseRowCount(array, path);

  PoseRows poses;
  poses.near = INFINITY;
  poses.far = -INFINITY;
  for (std::size_t i = 0; i < rows; ++i) {
    const double* row = &array.data[i * kPoseColumns];
    const std::string where = path.string() + " row " + std::to_string(i);
    const double h = row[4], w = row[9], f = row[14], near = row[15], far = row[16];
    if (!(h >= 1 && w >= 1 && h == std::floor(h) && w == std::floor(w) && h <= 1e6 && w <= 1e6)) {
      FailInvalid(where + ": H and W must be positive integers (H = " + Number(h) + ", W = " + Number(w) +
                  ")");
    }
    Camera camera;
    camera.width = static_cast<int>(w);
    camera.height = static_cast<int>(h);
    camera.fx = camera.fy = f;
    camera.cx = w / 2;
    camera.cy = h / 2;
    // LLFF stores the rotation's columns as [down, right, back]; OpenGL wants [right, up, back].
    for (int r = 0; r < 3; ++r) {
      camera.c2w(r, 0) = row[r * 5 + 1];
      camera.c2w(r, 1) = -row[r * 5 + 0];
      camera.c2w(r, 2) = row[r * 5 + 2];
      camera.c2w(r, 3) = row[r * 5 + 3];
    }
    CheckCamera(camera, where);
    if (!poses.cameras.empty() &&
        (camera.width != poses.cameras[0].width || camera.height != poses.cameras[0].height)) {
      FailInvalid(where + ": image size " + SizeText(camera.width, camera.height) + " differs from row 0's " +
                  SizeText(poses.cameras[0].width, poses.cameras[0].height));
    }
    CheckNearFar(near, far, where);
    poses.near = std::min(poses.near, near);
    poses.far = std::max(poses.far, far);
    poses.cameras.push_back(camera);
  }
  return poses;
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
  PoseRows poses = ReadPoseRows(dir / "poses_bounds.npy");
  std::vector<FrameFiles> frames = ListEndoNerfFrames(dir, poses.cameras.size());
  if (!options.frames.SelectsAll()) {
    const std::vector<int> picked = PickFrames(options.frames, frames.size(), dir.string());
    KeepPicked(picked, frames);
    KeepPicked(picked, poses.cameras);
  }
  const std::size_t n = poses.cameras.size();

  Clip clip;
  clip.source = dir.string();
  ReadFrames(frames, FrameReadOptionsOf(options), clip);
  MatchImageSize(frames[0].image, clip.width, clip.height, poses.cameras);

  clip.cameras = std::move(poses.cameras);
  clip.near = poses.near;
  clip.far = poses.far;
  CheckNearFar(clip.near, clip.far, (dir / "poses_bounds.npy").string() + " (over all rows)");
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
