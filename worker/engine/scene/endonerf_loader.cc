#include "worker/engine/scene/endonerf_loader.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <set>

#include "common/error.h"
#include "worker/engine/scene/clip_checks.h"
#include "worker/engine/scene/frame_reader.h"
#include "worker/engine/scene/json_file.h"
#include "worker/engine/scene/npy.h"

namespace endorecon::scene {
namespace {

namespace fs = std::filesystem;

constexpr std::size_t kPoseColumns = 17;

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
  if (!fs::is_regular_file(path)) FailInvalid(path.string() + ": file does not exist");
  const NpyArray array = ReadNpy(path);
  if (array.shape.size() != 2 || array.shape[1] != kPoseColumns) {
    std::string shape;
    for (std::size_t dim : array.shape) shape += (shape.empty() ? "" : ", ") + std::to_string(dim);
    FailInvalid(path.string() + ": expected an array of shape (N, 17), found (" + shape + ")");
  }
  const std::size_t rows = array.shape[0];
  if (rows == 0) FailInvalid(path.string() + ": zero frames (the array has no rows)");

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

// Where a per-frame folder and images/ part ways, by file name (stem): the first image without a
// file here, or the first file here without an image; empty when the names match.
std::string FirstUnpaired(const std::vector<fs::path>& files, const std::vector<fs::path>& images) {
  std::set<std::string> stems, image_stems;
  for (const auto& f : files) stems.insert(f.stem().string());
  for (const auto& f : images) image_stems.insert(f.stem().string());
  for (const auto& image : images) {
    if (!stems.count(image.stem().string()))
      return "no file named " + image.stem().string() + ".* for " + image.filename().string();
  }
  for (const auto& f : files) {
    if (!image_stems.count(f.stem().string())) return f.filename().string() + " names no image";
  }
  return "";
}

// The files of an optional folder: none when absent, otherwise exactly `count`, paired with
// `images` (when given) by their sorted order.
std::vector<fs::path> ListFolder(const fs::path& dir, const std::vector<std::string>& extensions,
                                 std::size_t count, bool required, const std::vector<fs::path>& images = {}) {
  if (!required && !fs::exists(dir)) return {};
  std::vector<fs::path> files = ListFiles(dir, extensions);
  if (files.size() != count) {
    const std::string unpaired = images.empty() ? "" : FirstUnpaired(files, images);
    FailInvalid(dir.string() + ": holds " + std::to_string(files.size()) +
                " files but poses_bounds.npy has " + std::to_string(count) +
                " rows (the counts of images, depth maps, masks and poses must be equal)" +
                (unpaired.empty() ? "" : "; " + unpaired));
  }
  // Files are paired with images by their sorted order: names that part ways (000004 beside image
  // 000003) usually mean a file is missing and another is extra.
  for (std::size_t i = 0; i < images.size() && i < files.size(); ++i) {
    if (files[i].stem() != images[i].stem()) {
      spdlog::warn("{}: {} is paired with images/{} by their sorted order, though their names differ ({})",
                   dir.string(), files[i].filename().string(), images[i].filename().string(),
                   FirstUnpaired(files, images));
      break;
    }
  }
  return files;
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
  const std::size_t n = poses.cameras.size();

  std::vector<std::string> depth_extensions = ImageExtensions();
  depth_extensions.push_back(".npy");
  const std::vector<fs::path> images = ListFolder(dir / "images", ImageExtensions(), n, true);
  const std::vector<fs::path> depths = ListFolder(dir / "depth", depth_extensions, n, false, images);
  const std::vector<fs::path> masks = ListFolder(dir / "masks", ImageExtensions(), n, false, images);
  const std::vector<fs::path> eval_masks = ListFolder(dir / "gt_masks", ImageExtensions(), n, false, images);
  const std::vector<fs::path> rights = ListFolder(dir / "images_right", ImageExtensions(), n, false, images);

  std::vector<FrameFiles> frames(n);
  for (std::size_t i = 0; i < n; ++i) {
    frames[i].image = images[i];
    if (!depths.empty()) frames[i].depth = depths[i];
    if (!masks.empty()) frames[i].tool_mask = masks[i];
    if (!eval_masks.empty()) frames[i].eval_mask = eval_masks[i];
    if (!rights.empty()) frames[i].right_image = rights[i];
  }

  Clip clip;
  clip.source = dir.string();
  FrameReadOptions read_options;
  read_options.max_pixels_per_frame = options.max_pixels_per_frame;
  read_options.alpha_background = options.alpha_background;
  ReadFrames(frames, read_options, clip);
  MatchImageSize(images[0], clip.width, clip.height, poses.cameras);

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
  }
  clip.is_static = options.force_static || n == 1;
  return clip;
}

}  // namespace endorecon::scene
