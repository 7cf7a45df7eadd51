#include "worker/engine/scene/clip_checks.h"

#include <spdlog/spdlog.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "common/error.h"
#include "worker/engine/scene/clip.h"

namespace endorecon::scene {
namespace {

std::string Number(double value) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.6g", value);
  return text;
}

}  // namespace

void CheckCamera(const Camera& camera, const std::string& where) {
  CheckIntrinsics(camera.fx, camera.fy, camera.cx, camera.cy, camera.width, camera.height, where);
  CheckRigidPose(camera.c2w.data(), where);
}

void CheckClipGeometry(const Clip& clip, const std::string& where) {
  double spread = 0;
  for (const Camera& a : clip.cameras) {
    for (const Camera& b : clip.cameras) {
      spread = std::max(spread, (a.c2w.col(3) - b.c2w.col(3)).stableNorm());
      if (spread > kMostCameraSpread * clip.far) {
        FailInvalid(where + ": the cameras' centres lie " + Number(spread) + " apart, more than " +
                    Number(kMostCameraSpread) + " times the far bound (" + Number(clip.far) +
                    "): a pose's translation is likely in other units than the depth bounds");
      }
    }
  }
  // The results (point clouds, meshes) hold single-precision coordinates, in the clip's frame: far
  // from its origin they step by more than a thousandth of the depth range (poses translated by 1e9
  // came back as points on a grid of 64 units; found 2026-12-05).
  double farthest = 0;
  for (const Camera& camera : clip.cameras) farthest = std::max(farthest, camera.c2w.col(3).stableNorm());
  const double step = farthest * std::numeric_limits<float>::epsilon();
  if (step > 1e-3 * (clip.far - clip.near)) {
    spdlog::warn(
        "{}: the cameras lie up to {} from the origin, where the results' single-precision coordinates "
        "step by about {}, more than a thousandth of the depth range ({} to {}): move the poses' origin "
        "into the scene for exact point clouds and meshes",
        where, Number(farthest), Number(step), Number(clip.near), Number(clip.far));
  }
  std::size_t outside = 0, seen = 0;
  for (const auto& frame : clip.depth) {
    for (std::size_t i = 0; i < frame.size(); i += 61) {
      if (!(frame[i] > 0)) continue;
      ++seen;
      outside += InOtherUnits(frame[i], clip.near, clip.far);
    }
  }
  if (seen > 0 && 2 * outside > seen) {
    spdlog::warn(
        "{}: {:.0f}% of the depth priors lie outside [near / 2, 2 far] = [{}, {}]: are the depth "
        "maps in the poses' units? The depth loss and depth-guided sampling follow them as they are",
        where, 100.0 * double(outside) / double(seen), Number(0.5 * clip.near), Number(2 * clip.far));
  }
}

void CheckFrameLimit(int width, int height, std::size_t max_pixels, const std::string& where) {
  const auto pixels = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
  if (pixels > max_pixels) {
    // The input's fault, not a resource another worker has: INVALID_ARGUMENT, so the job fails at once
    // (as RESOURCE_EXHAUSTED it was retried on three leases and read as vanished workers).
    Fail(ErrorCode::kInvalidArgument, where + ": frames of " + SizeText(width, height) + " (" +
                                          std::to_string(pixels) + " pixels) exceed the limit of " +
                                          std::to_string(max_pixels) + " pixels per frame");
  }
}

}  // namespace endorecon::scene
