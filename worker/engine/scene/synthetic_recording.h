// The raw stereo recording behind a synthetic clip, as a real stereo endoscope records it: each
// eye with its own intrinsics and lens distortion (OpenCV's model), the right eye slightly rotated
// and off the ideal baseline, and the calibration that describes the rig. `endorecon-worker
// prepare` turns it back into a clip; the truth it should reach is the scene itself
// (RenderSyntheticView). Written by WriteSyntheticClip under <clip>/recording/ (SynthOptions::recording):
//   left/NNNNNN.png, right/NNNNNN.png   the raw frames (tool drawn)
//   masks/NNNNNN.png                    255 where the raw left eye sees the tool          [tool]
//   calibration.yaml                    the rig as cv::FileStorage writes it: K1 D1 K2 D2 R T,
//                                       image_width, image_height (OpenCV stereo calibration)
//   poses.json                          {"convention": "opencv", "poses": [4x4 ...]}: the raw
//                                       left eye's camera-to-world per frame
//   checkerboard/left/, checkerboard/right/  the rig looking at a checkerboard in
//                                       SynthOptions::checkerboard_views poses (for `endorecon-worker
//                                       calibrate`)
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <filesystem>
#include <vector>

#include "worker/engine/scene/camera.h"
#include "worker/engine/scene/synthetic_scene.h"

namespace endorecon::scene {

// One eye in OpenCV's conventions: pixel centres at integer coordinates, camera x right, y down,
// z forward; distortion (k1, k2, p1, p2, k3).
struct RigEye {
  Eigen::Matrix3d k = Eigen::Matrix3d::Identity();
  std::array<double, 5> distortion{};
};

struct StereoRig {
  int width = 0, height = 0;
  RigEye left, right;
  // X_right = rotation * X_left + translation (points in the eyes' camera frames), as
  // cv::stereoCalibrate's R and T. The right eye's centre is near (baseline, 0, 0) in the left's frame.
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
};

// The checkerboard of the calibration views: inner corners (columns x rows) and square size (clip units).
constexpr int kCheckerboardColumns = 9, kCheckerboardRows = 6;
constexpr double kCheckerboardSquare = 4.0;

// The rig of a synthetic clip of options.width x options.height: f about 0.9 W, principal points a
// percent off centre, barrel distortion (k1 about -0.2), the right eye 5 units to the right with
// about 0.6 degrees of rotation and a small vertical and depth offset. Fixed (independent of the seed).
StereoRig SyntheticRig(const SynthOptions& options);

// Writes `dir` (recording/ of the clip) as described above. Throws Error(kUnavailable) when a
// file cannot be written.
void WriteSyntheticRecording(const SyntheticScene& scene, const SynthOptions& options,
                             const std::filesystem::path& dir);

// What a pinhole camera (any pose, e.g. the rectified camera a prepared clip has) sees at time t:
// per pixel, row-major, the tissue's and the first surface's z-depth in that camera, and 1 where
// the tool is in front.
struct SyntheticView {
  std::vector<float> tissue_depth, depth;
  std::vector<std::uint8_t> tool;
};
SyntheticView RenderSyntheticView(const SyntheticScene& scene, const Camera& camera, double time);

}  // namespace endorecon::scene
