// Synthetic stereo recordings (the raw pair behind a synthetic clip, synthetic_recording.h) for the
// tests of worker/prepare, and the truth a prepared clip should reach: the scene seen through the
// prepared clip's own (rectified) camera.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/core/eigen.hpp>
#include <opencv2/imgcodecs.hpp>
#include <vector>

#include "tests/unit/temp_dir.h"
#include "worker/engine/scene/clip.h"
#include "worker/engine/scene/synthetic_clip.h"
#include "worker/engine/scene/synthetic_recording.h"
#include "worker/prepare/prepare_clip.h"
#include "worker/prepare/stereo_rectifier.h"

namespace endorecon::testing {

// A clip with its recording; the checkerboard views only when asked for (they take time).
inline scene::SynthOptions RecordingOptions(int width, int height, int frames, int checkerboard_views = 0) {
  scene::SynthOptions options;
  options.width = width;
  options.height = height;
  options.frames = frames;
  options.recording = true;
  options.checkerboard_views = checkerboard_views;
  return options;
}

inline nlohmann::json ReadJson(const std::filesystem::path& path) {
  std::ifstream in(path);
  return nlohmann::json::parse(in);
}

// The options that prepare a synthetic clip's recording (two PNG folders, its calibration, its masks).
inline prepare::PrepareOptions RecordingPrepareOptions(const std::filesystem::path& synth,
                                                       const std::filesystem::path& out) {
  prepare::PrepareOptions options;
  options.recording = {
      prepare::StereoLayout::kTwoSources, synth / "recording/left", synth / "recording/right", {}};
  options.calibration = {synth / "recording/calibration.yaml"};
  options.masks = synth / "recording/masks";
  options.out = out;
  return options;
}

// The prepared clip's camera at its frame `frame` (prepare.json), in the synthetic scene's world:
// the raw left eye's pose (the scene's) turned by the inverse of the rectifying rotation.
inline scene::Camera TruthCamera(const scene::SyntheticScene& scene, const scene::SynthOptions& options,
                                 const nlohmann::json& report, int frame) {
  const auto& rotation = report["rectification"]["left_rotation"];
  Eigen::Matrix3d r1;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) r1(r, c) = rotation[r][c].get<double>();
  }
  const Eigen::Matrix3d flip = Eigen::Vector3d(1, -1, -1).asDiagonal();
  const int recording_frame = report["frames"][frame]["recording_frame"].get<int>();
  const Eigen::Matrix<double, 3, 4> pose = scene.LeftPose(scene::FrameTime(options, recording_frame));
  scene::Camera camera;
  camera.width = report["rectification"]["size"][0].get<int>();
  camera.height = report["rectification"]["size"][1].get<int>();
  camera.fx = camera.fy = report["rectification"]["focal_px"].get<double>();
  camera.cx = camera.width / 2.0;
  camera.cy = camera.height / 2.0;
  camera.c2w.leftCols<3>() = pose.leftCols<3>() * flip * r1.transpose() * flip;
  camera.c2w.col(3) = pose.col(3);
  return camera;
}

// A prepared clip's depth against the truth, over its tissue pixels: not the tool (in truth) and
// not excluded by the clip's own masks. `visible` counts the tissue pixels the right eye sees too
// (the only ones stereo can measure: a strip along the left edge is outside the right view).
struct DepthScore {
  double rmse = 0, mae = 0;
  long tissue = 0, visible = 0, valid = 0;
  double valid_share() const { return static_cast<double>(valid) / tissue; }
  double valid_visible_share() const { return static_cast<double>(valid) / visible; }
};

inline DepthScore ScoreDepth(const scene::SyntheticScene& scene, const scene::SynthOptions& options,
                             const scene::Clip& clip, const nlohmann::json& report) {
  DepthScore score;
  double squares = 0, absolute = 0;
  const double fb =
      report["rectification"]["focal_px"].get<double>() * report["rectification"]["baseline"].get<double>();
  for (int f = 0; f < clip.frame_count(); ++f) {
    const int recording_frame = report["frames"][f]["recording_frame"].get<int>();
    const scene::SyntheticView truth = scene::RenderSyntheticView(
        scene, TruthCamera(scene, options, report, f), scene::FrameTime(options, recording_frame));
    for (int y = 0; y < clip.height; ++y) {
      for (int x = 0; x < clip.width; ++x) {
        const std::size_t p = static_cast<std::size_t>(y) * clip.width + x;
        if (truth.tool[p] || (clip.has_masks() && clip.tool_mask[f][p])) continue;
        ++score.tissue;
        score.visible += x + 0.5 - fb / truth.tissue_depth[p] >= 0;
        const float z = clip.depth[f][p];
        if (z <= 0) continue;
        ++score.valid;
        const double e = z - truth.tissue_depth[p];
        squares += e * e;
        absolute += std::abs(e);
      }
    }
  }
  score.rmse = std::sqrt(squares / std::max(1L, score.valid));
  score.mae = absolute / std::max(1L, score.valid);
  return score;
}

// The synthetic rig's true calibration.
inline prepare::StereoCalibration SyntheticCalibration(const scene::SynthOptions& options) {
  const scene::StereoRig rig = scene::SyntheticRig(options);
  prepare::StereoCalibration c;
  c.image_size = {options.width, options.height};
  cv::Mat k1, k2, r, t;
  cv::eigen2cv(rig.left.k, k1);
  cv::eigen2cv(rig.right.k, k2);
  cv::eigen2cv(rig.rotation, r);
  cv::eigen2cv(rig.translation, t);
  c.k1 = cv::Matx33d(k1);
  c.k2 = cv::Matx33d(k2);
  c.d1 = cv::Mat(1, 5, CV_64F, const_cast<double*>(rig.left.distortion.data())).clone();
  c.d2 = cv::Mat(1, 5, CV_64F, const_cast<double*>(rig.right.distortion.data())).clone();
  c.r = cv::Matx33d(r);
  c.t = cv::Vec3d(t);
  c.kind = "opencv";
  return c;
}

// Points at depths 45-110 in front of the rectified left camera, over its whole frame.
inline std::vector<cv::Point3d> PointsInView(const prepare::RectifiedCamera& camera) {
  std::vector<cv::Point3d> points;
  cv::RNG random(3);
  for (int i = 0; i < 500; ++i) {
    const double u = random.uniform(0.0, camera.size.width - 1.0),
                 v = random.uniform(0.0, camera.size.height - 1.0);
    const double z = random.uniform(45.0, 110.0);
    const cv::Vec3d rectified(z * (u - (camera.size.width - 1) / 2.0) / camera.focal,
                              z * (v - (camera.size.height - 1) / 2.0) / camera.focal, z);
    const cv::Vec3d raw = camera.left_rotation.t() * rectified;
    points.emplace_back(raw[0], raw[1], raw[2]);
  }
  return points;
}

// The worst row difference of the points between the rectified eyes, and their worst distance
// from where the rectified left camera projects them.
inline std::pair<double, double> EpipolarAndProjectionError(const prepare::StereoCalibration& truth,
                                                            const prepare::StereoRectifier& rectifier) {
  const prepare::RectifiedCamera& camera = rectifier.camera();
  const std::vector<cv::Point3d> points = PointsInView(camera);
  std::vector<cv::Point2d> left, right;
  cv::projectPoints(points, cv::Vec3d(), cv::Vec3d(), truth.k1, truth.d1, left);
  cv::Vec3d rotation;
  cv::Rodrigues(truth.r, rotation);
  cv::projectPoints(points, rotation, truth.t, truth.k2, truth.d2, right);
  const auto l = rectifier.RectifyPoints(0, left), r = rectifier.RectifyPoints(1, right);
  double epipolar = 0, projection = 0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    epipolar = std::max(epipolar, std::abs(l[i].y - r[i].y));
    const cv::Vec3d x = camera.left_rotation * cv::Vec3d(points[i].x, points[i].y, points[i].z);
    const cv::Point2d expected(camera.focal * x[0] / x[2] + (camera.size.width - 1) / 2.0,
                               camera.focal * x[1] / x[2] + (camera.size.height - 1) / 2.0);
    projection = std::max(projection, cv::norm(l[i] - expected));
  }
  return {epipolar, projection};
}

}  // namespace endorecon::testing
