#include "worker/engine/scene/transforms_clip.h"

#include <spdlog/spdlog.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <numbers>
#include <optional>
#include <vector>

#include "common/error.h"
#include "worker/engine/scene/camera_json.h"
#include "worker/engine/scene/clip_checks.h"

namespace endorecon::scene {
namespace {

using nlohmann::json;

// Near/far derived from depth maps or camera distances (transforms_loader.h).
constexpr double kDepthNearFactor = 0.8, kDepthFarFactor = 1.2;
constexpr double kDistanceNearFactor = 0.05, kDistanceFarFactor = 2.5;
constexpr double kObjectRadiusFactor = 0.5;

void SetTimes(const json& frames, const std::string& file, Clip& clip) {
  const std::size_t n = frames.size();
  std::vector<std::optional<double>> times(n);
  for (std::size_t i = 0; i < n; ++i)
    times[i] = OptionalNumber(frames[i], "time", file + " frame " + std::to_string(i));
  clip.times.assign(n, 0.f);
  const std::size_t timed = static_cast<std::size_t>(
      std::count_if(times.begin(), times.end(), [](auto& t) { return t.has_value(); }));
  if (timed == 0) {
    clip.is_static = true;
    return;
  }
  if (timed != n) {
    const std::size_t missing =
        static_cast<std::size_t>(std::find(times.begin(), times.end(), std::nullopt) - times.begin());
    FailInvalid(file + " frame " + std::to_string(missing) + ": no \"time\" while " + std::to_string(timed) +
                " of " + std::to_string(n) + " frames have one (give all frames a time, or none)");
  }
  double lo = INFINITY, hi = -INFINITY;
  for (const auto& t : times) {
    lo = std::min(lo, *t);
    hi = std::max(hi, *t);
  }
  const bool rescale = lo < 0 || hi > 1;
  if (!std::isfinite(hi - lo)) {
    FailInvalid(file + ": the frames' times span [" + std::to_string(lo) + ", " + std::to_string(hi) +
                "], too wide to rescale to [0, 1]");
  }
  if (rescale) spdlog::info("{}: times span [{}, {}]; rescaling them to [0, 1]", file, lo, hi);
  for (std::size_t i = 0; i < n; ++i) {
    const double t = !rescale ? *times[i] : hi > lo ? (*times[i] - lo) / (hi - lo) : 0.0;
    clip.times[i] = static_cast<float>(t);
  }
  clip.is_static = hi == lo;
}

// A centred rig: at least three cameras, each looking at the origin (its optical axis passes within
// kCentredAxisMiss of its distance from it) from directions at least kCentredSpreadDeg apart from
// their mean, as NeRF-synthetic and other object captures stand. A forward-facing capture (every
// camera on one side) is not one.
constexpr double kCentredAxisMiss = 0.25, kCentredSpreadDeg = 30;

bool IsCentredRig(const std::vector<Camera>& cameras) {
  if (cameras.size() < 3) return false;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const Camera& camera : cameras) {
    const Eigen::Vector3d origin = camera.c2w.col(3);
    const Eigen::Vector3d forward = -camera.c2w.col(2).normalized();  // OpenGL: looking down -z
    const double distance = origin.norm();
    if (!(distance > 1e-9)) return false;
    const double along = -origin.dot(forward);  // how far ahead the origin's closest point lies
    if (!(along > 0) || (origin + along * forward).norm() > kCentredAxisMiss * distance) return false;
    mean += origin / distance;
  }
  if (!(mean.norm() > 1e-9)) return true;  // directions cancel: cameras all round the object
  mean.normalize();
  double spread = 1;
  for (const Camera& camera : cameras) spread = std::min(spread, mean.dot(camera.c2w.col(3).normalized()));
  return spread < std::cos(kCentredSpreadDeg * std::numbers::pi / 180);
}

void SetNearFar(const json& top, const std::string& file, Clip& clip) {
  const std::optional<double> near = OptionalNumber(top, "near", file);
  const std::optional<double> far = OptionalNumber(top, "far", file);
  std::vector<double> distances;  // of the cameras from the origin, ascending
  for (const Camera& camera : clip.cameras) distances.push_back(camera.c2w.col(3).norm());
  std::sort(distances.begin(), distances.end());
  const double median = distances[distances.size() / 2];
  // Object captures: the object fills at most the sphere of half the median camera distance (the
  // NeRF-synthetic rig: cameras at 4.03, near 2, far 6).
  if (IsCentredRig(clip.cameras)) clip.object_radius = kObjectRadiusFactor * median;
  double derived_near = 0, derived_far = 0;
  if (!near || !far) {
    float lo = INFINITY, hi = 0;
    for (const std::vector<float>& depth : clip.depth) {
      for (float z : depth) {
        if (z > 0) lo = std::min(lo, z);
        hi = std::max(hi, z);
      }
    }
    if (hi > 0) {
      derived_near = kDepthNearFactor * lo;
      derived_far = kDepthFarFactor * hi;
    } else if (clip.object_radius > 0) {
      derived_near = std::max(kDistanceNearFactor * median, distances.front() - clip.object_radius);
      derived_far = distances.back() + clip.object_radius;
    } else {
      if (!(median > 1e-9)) {
        FailInvalid(file +
                    ": cannot derive near and far (no depth maps, and the cameras sit at the origin); "
                    "add top-level \"near\" and \"far\"");
      }
      derived_near = kDistanceNearFactor * median;
      derived_far = kDistanceFarFactor * median;
    }
    spdlog::info("{}: derived depth bounds near = {:.6g}, far = {:.6g}", file, near.value_or(derived_near),
                 far.value_or(derived_far));
  }
  clip.near = near.value_or(derived_near);
  clip.far = far.value_or(derived_far);
  CheckNearFar(clip.near, clip.far, file);
  if (clip.object_radius > 0) {
    spdlog::info("{}: the cameras stand around the origin; the object is taken to lie within {:.6g} of it",
                 file, clip.object_radius);
  }
}

}  // namespace

void FinishTransformsClip(const json& top, const std::string& file, Clip& clip) {
  const json& frames = top.at("frames");
  for (std::size_t i = 0; i < frames.size(); ++i) {
    clip.cameras.push_back(
        CameraFromJson(frames[i], top, clip.width, clip.height, file + " frame " + std::to_string(i), file));
  }
  SetTimes(frames, file, clip);
  SetNearFar(top, file, clip);
}

}  // namespace endorecon::scene
