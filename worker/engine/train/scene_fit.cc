#include "worker/engine/train/scene_fit.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "worker/engine/field/hash_grid.h"
#include "worker/engine/scene/exposure_change.h"
#include "worker/engine/scene/scene_box.h"
#include "worker/engine/train/still_clip.h"

namespace endorecon::train {
namespace {

// The training frames (all frames when none are named) in time order, and their distinct times.
struct TrainingTimes {
  std::vector<int> frames;
  std::vector<float> times;
};

TrainingTimes InTimeOrder(const scene::Clip& clip, std::vector<int> frames) {
  if (frames.empty()) {
    for (int f = 0; f < clip.frame_count(); ++f) frames.push_back(f);
  }
  std::sort(frames.begin(), frames.end(),
            [&](int a, int b) { return clip.times[std::size_t(a)] < clip.times[std::size_t(b)]; });
  std::vector<float> times;
  for (const int f : frames) {
    const float t = clip.times[std::size_t(f)];
    if (times.empty() || t > times.back()) times.push_back(t);
  }
  return {std::move(frames), std::move(times)};
}

// Resolves config.exposure and gives the field a knot at each training frame's time (distinct times
// only: a static clip's frames share one).
// Records a part left out or kept, and why (SceneFit::left_out, SceneFit::kept).
using Note = std::function<void(const std::string& what, const std::string& why)>;

void FitExposure(const scene::Clip& clip, TrainConfig& config, TrainingTimes training, const Note& leave_out,
                 const Note& keep) {
  if (!config.field.exposure_times.empty()) return;  // fitted already
  const auto& [frames, times] = training;
  if (config.exposure == "auto" && frames.size() < 2) {
    config.exposure = "off";
    leave_out("per-frame exposure gains", "training sees one frame: there is no next to change from");
  }
  if (config.exposure == "auto") {
    const double change = scene::ExposureChange(clip, frames);
    config.exposure = change > config.exposure_threshold ? "on" : "off";
    const std::string why = fmt::format(
        "the frames' brightness changes by {:.2g}% from one to the next (median, beyond what the pixels' "
        "noise and count leave uncertain), {} {:.2g}% (exposure_threshold)",
        100 * change, config.exposure == "on" ? "more than" : "at most", 100 * config.exposure_threshold);
    (config.exposure == "on" ? keep : leave_out)("per-frame exposure gains", why);
  }
  if (config.exposure == "on" && times.size() < 2) {
    config.exposure = "off";
    leave_out("per-frame exposure gains", "training sees fewer than two distinct times");
  }
  if (config.exposure == "on") config.field.exposure_times = std::move(training.times);
}

}  // namespace

int UncertaintyMapStride(int width, int height, int frames, const TrainConfig& config) {
  const double probes = kMapProbeShare * config.adaptive_refresh * config.rays_per_batch;
  int stride = std::max(1, config.adaptive_map_stride);
  const auto cells = [&](int s) { return double((width + s - 1) / s) * ((height + s - 1) / s) * frames; };
  while (cells(stride) > probes && stride < std::max(width, height)) ++stride;
  return stride;
}

scene::Camera SceneFit::preview_camera(const scene::Camera& camera) const {
  const double k = std::min(1.0, double(preview_width) / camera.width);
  scene::Camera small = camera;
  small.width = std::max(1, int(std::lround(camera.width * k)));
  small.height = std::max(1, int(std::lround(camera.height * k)));
  small.fx *= k;
  small.fy *= k;
  small.cx *= k;
  small.cy *= k;
  return small;
}

SceneFit FitToScene(const scene::Clip& clip, TrainConfig& config, std::vector<int> train_frames) {
  SceneFit fit;
  const Note leave_out = [&](const std::string& what, const std::string& why) {
    fit.left_out.push_back({{"what", what}, {"why", why}});
  };
  const Note keep = [&](const std::string& what, const std::string& why) {
    fit.kept.push_back({{"what", what}, {"why", why}});
  };
  if (!clip.has_masks()) leave_out("tool-mask handling", "the clip has no masks/");
  if (!clip.bounds_fitted.empty()) leave_out("the depth bounds beyond the depth priors", clip.bounds_fitted);
  if (!clip.has_depth()) {
    leave_out("depth loss and depth-guided sampling", "the clip has no depth/");
    config.depth_weight = 0;
  }
  // An object capture on transparency is seen on white (NeRF-synthetic's convention); one with opaque
  // images stands in front of a real backdrop, which a colour per direction fits and black does not;
  // an endoscope sees dark beyond its light.
  if (config.background == "auto") {
    config.background = clip.transparent ? "white" : clip.object_radius > 0 ? "learned" : "black";
  }
  config.field.learned_background = config.background == "learned";
  TrainingTimes training = InTimeOrder(clip, std::move(train_frames));
  std::string still;
  if (clip.is_static) {
    still = "the clip is static";
  } else if (config.field.deformation.enabled && config.still_threshold_px > 0) {
    const Stillness s = MeasureStillness(clip, training.frames, config.still_threshold_px);
    if (!s.still) {
      keep("deformation network",
           s.tested
               ? fmt::format(
                     "the clip's tissue moves: in a frame tried, 5% of it moves {:.2g} px or more from the "
                     "first training frame (still_threshold_px {:.2g})",
                     s.motion_px, config.still_threshold_px)
               : "not tested for stillness: " + s.why);
    } else {
      still = fmt::format(
          "the clip's tissue stands still: with the camera fixed, 95% of it moves less than {:.2g} px "
          "from the first training frame in each of the {} others (at most {:.2g} px; still_threshold_px)",
          config.still_threshold_px, s.frames, s.motion_px);
    }
  }
  if (!still.empty()) {
    leave_out("deformation network", still);
    config.field.deformation.enabled = false;
    if (config.field.heads.color_time_frequencies > 0) {
      leave_out("the colour head's time inputs", still);
      config.field.heads.color_time_frequencies = 0;
    }
  }
  if (config.adaptive_sampling && config.adaptive_ray_fraction > 0) {
    config.adaptive_map_stride =
        UncertaintyMapStride(clip.width, clip.height, int(training.frames.size()), config);
  }
  // The times the field is trained at (field_config.h: it holds its state outside them).
  if (!training.times.empty()) config.field.trained_times = {training.times.front(), training.times.back()};
  FitExposure(clip, config, std::move(training), leave_out, keep);
  // Finest useful grid resolution: two cells per pixel footprint at the typical depth, over the box.
  const scene::SceneBox box = scene::ClipBox(clip);
  double focal = 0;
  for (const auto& camera : clip.cameras) focal = std::max({focal, camera.fx, camera.fy});
  const double footprint = scene::TypicalDepth(clip) / std::max(focal, 1e-9);
  // In double first: a box far larger than the footprint (near 0, far 1e11) overflowed the int and
  // read "levels above -2147483648 cells" (found 2026-12-05).
  const double cells = std::ceil(2.0 * box.scale() / std::max(footprint, 1e-12));
  const int useful =
      cells >= double(std::numeric_limits<int>::max()) ? std::numeric_limits<int>::max() : int(cells);
  if (config.field.grids.max_resolution <= 0 || useful < config.field.grids.max_resolution) {
    config.field.grids.max_resolution = useful;
  }
  int dropped = 0;
  for (std::size_t i = 0; i < config.field.grids.base_resolutions.size(); ++i) {
    dropped += config.field.grids.levels - field::LevelsUpToResolution(config.field.grids.Grid(int(i)),
                                                                       config.field.grids.max_resolution);
  }
  if (dropped > 0) {
    leave_out(std::to_string(dropped) + " hash-grid levels above " +
                  std::to_string(config.field.grids.max_resolution) + " cells per axis",
              "finer than half a pixel's footprint at the typical depth");
  }
  return fit;
}

}  // namespace endorecon::train
