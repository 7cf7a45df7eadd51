#include "worker/engine/scene/clip_loader.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cstdint>
#include <optional>
#include <vector>

#include "common/clip_files.h"
#include "common/error.h"
#include "worker/engine/scene/clip_checks.h"
#include "worker/engine/scene/depth_bounds.h"
#include "worker/engine/scene/endonerf_loader.h"
#include "worker/engine/scene/frame_pick.h"
#include "worker/engine/scene/frame_reader.h"
#include "worker/engine/scene/transforms_loader.h"

namespace endorecon::scene {
namespace {

namespace fs = std::filesystem;

// gt/ of the clip in `clip_dir`: one file a frame of the clip folder, of which the loaded clip took
// `options.frames`.
void LoadGroundTruth(const fs::path& clip_dir, const LoadOptions& options, Clip& clip) {
  const fs::path dir = clip_dir / "gt";
  std::vector<FrameFiles> frames =
      ListGroundTruthFrames(dir, options.frames.SelectsAll() ? static_cast<std::size_t>(clip.frame_count())
                                                             : ListClipFrames(clip_dir).size());
  if (!options.frames.SelectsAll())
    KeepPicked(PickFrames(options.frames, frames.size(), clip_dir.string()), frames);
  Clip truth;
  truth.source = dir.string();
  truth.width = clip.width;
  truth.height = clip.height;
  FrameReadOptions read_options;
  read_options.max_pixels_per_frame = options.max_pixels_per_frame;
  read_options.alpha_background = options.alpha_background;
  ReadFrames(frames, read_options, truth);
  clip.gt_rgb = std::move(truth.rgb);
  clip.gt_depth = std::move(truth.depth);
}

}  // namespace

Clip LoadClip(const fs::path& dir, const LoadOptions& options) {
  if (!fs::exists(dir)) Fail(ErrorCode::kNotFound, dir.string() + ": clip folder does not exist");
  if (!fs::is_directory(dir)) {
    FailInvalid(dir.string() +
                ": a file, not a clip: a clip is a folder in the EndoNeRF or transforms.json layout, or a "
                "DICOM recording (docs/formats.md); a video becomes a DICOM recording with `endorecon-worker "
                "to-dicom VIDEO -o recording.dcm`");
  }
  Clip clip;
  const std::optional<ClipLayout> layout = FindClipLayout(dir);
  // A synthetic clip's ground truth (gt/, loaded after the frames) takes colour and depth per pixel
  // more: counted in the frames' memory check.
  LoadOptions loading = options;
  if (fs::is_directory(dir / "gt")) loading.extra_bytes_per_pixel += 3 + 4;
  if (layout == ClipLayout::kTransforms) {
    clip = LoadTransformsClip(dir, loading);
  } else if (layout == ClipLayout::kEndoNerf) {
    clip = LoadEndoNerfClip(dir, loading);
  } else {
    FailInvalid(dir.string() +
                ": not a clip: found neither transforms.json (transforms.json layout) nor "
                "poses_bounds.npy (EndoNeRF layout)");
  }
  if (fs::is_directory(dir / "gt")) LoadGroundTruth(dir, options, clip);
  CheckClipGeometry(clip, dir.string());
  if (options.fit_depth_bounds) clip.bounds_fitted = FitBoundsToPriors(clip);
  if (!clip.bounds_fitted.empty()) spdlog::warn("{}: {}", dir.string(), clip.bounds_fitted);
  // Frames with nothing in them (a lens cap, an exposure of 0) train a black field without a word.
  const bool all_black =
      std::all_of(clip.rgb.begin(), clip.rgb.end(), [](const std::vector<std::uint8_t>& image) {
        return std::all_of(image.begin(), image.end(), [](std::uint8_t v) { return v < 2; });
      });
  if (all_black && !clip.rgb.empty())
    spdlog::warn("{}: every frame is black (a lens cap, or an exposure of 0?)", dir.string());
  return clip;
}

}  // namespace endorecon::scene
