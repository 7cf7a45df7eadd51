#include "worker/engine/scene/synthetic_recording.h"

#include <tbb/parallel_for.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/core/eigen.hpp>

#include "common/error.h"
#include "worker/engine/scene/portable_random.h"
#include "worker/engine/scene/synthetic_files.h"

namespace endorecon::scene {
namespace {

namespace fs = std::filesystem;
using Pose = Eigen::Matrix<double, 3, 4>;  // camera-to-world [R | t]

// OpenCV's camera axes (x right, y down, z forward) in OpenGL's (x right, y up, z back) and back.
const Eigen::Matrix3d kFlipYz = Eigen::Vector3d(1, -1, -1).asDiagonal();

// The normalised ray (x, y) of every pixel of an eye, row-major; `samples` x `samples` rays per
// pixel spread evenly over it (1: the pixel centre). OpenCV inverts its own distortion model
// (iteratively; here to 1e-12 pixels) so the frames match the calibration file exactly.
std::vector<cv::Point2d> PixelRays(const RigEye& eye, int width, int height, int samples) {
  std::vector<cv::Point2d> pixels;
  pixels.reserve(static_cast<std::size_t>(width) * height * samples * samples);
  for (int v = 0; v < height; ++v) {
    for (int u = 0; u < width; ++u) {
      for (int sv = 0; sv < samples; ++sv) {
        for (int su = 0; su < samples; ++su) {
          pixels.emplace_back(u + (su + 0.5) / samples - 0.5, v + (sv + 0.5) / samples - 0.5);
        }
      }
    }
  }
  cv::Mat k, d(1, 5, CV_64F, const_cast<double*>(eye.distortion.data()));
  cv::eigen2cv(eye.k, k);
  std::vector<cv::Point2d> rays;
  cv::undistortPoints(pixels, rays, k, d, cv::noArray(), cv::noArray(),
                      cv::TermCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 200, 1e-12));
  return rays;
}

// The eyes' camera-to-world poses in OpenCV axes, with the left eye at `left_gl` (OpenGL axes).
std::array<Pose, 2> EyePoses(const StereoRig& rig, const Pose& left_gl) {
  Pose left;
  left.leftCols<3>() = left_gl.leftCols<3>() * kFlipYz;
  left.col(3) = left_gl.col(3);
  Pose right;  // right-to-left: X_left = R^T (X_right - T)
  right.leftCols<3>() = left.leftCols<3>() * rig.rotation.transpose();
  right.col(3) = left.col(3) - left.leftCols<3>() * rig.rotation.transpose() * rig.translation;
  return {left, right};
}

// `samples` x `samples` rays per pixel (PixelRays' order), averaged: a sensor integrates over its
// pixels, so a real recording's fine texture does not alias as point samples would.
void RenderEye(const SyntheticScene& scene, const SyntheticScene::State& state, const Pose& eye,
               const std::vector<cv::Point2d>& rays, int samples, cv::Mat& bgr, cv::Mat* tool) {
  const int per_pixel = samples * samples;
  tbb::parallel_for(0, bgr.rows, [&](int v) {
    double guess = 0;
    for (int u = 0; u < bgr.cols; ++u) {
      std::array<float, 3> sum{};
      int tool_hits = 0;
      for (int s = 0; s < per_pixel; ++s) {
        const cv::Point2d& ray = rays[(static_cast<std::size_t>(v) * bgr.cols + u) * per_pixel + s];
        const Eigen::Vector3d direction = eye.leftCols<3>() * Eigen::Vector3d(ray.x, ray.y, 1);
        const SceneHit hit = scene.TraceAlong(state, eye.col(3), direction, guess);
        guess = hit.tissue_depth;
        for (int c = 0; c < 3; ++c) sum[c] += std::clamp(hit.rgb[c], 0.f, 1.f) / per_pixel;
        tool_hits += hit.tool;
      }
      PutRgb(bgr, u, v, sum);
      if (tool) tool->at<std::uint8_t>(v, u) = 2 * tool_hits >= per_pixel ? 255 : 0;
    }
  });
}

void WriteCalibration(const StereoRig& rig, const fs::path& path) {
  cv::FileStorage file(path.string(), cv::FileStorage::WRITE);
  if (!file.isOpened()) Fail(ErrorCode::kUnavailable, "cannot write " + path.string());
  cv::Mat k1, k2, r, t;
  cv::eigen2cv(rig.left.k, k1);
  cv::eigen2cv(rig.right.k, k2);
  cv::eigen2cv(rig.rotation, r);
  cv::eigen2cv(rig.translation, t);
  file << "image_width" << rig.width << "image_height" << rig.height;
  file << "K1" << k1 << "D1" << cv::Mat(1, 5, CV_64F, const_cast<double*>(rig.left.distortion.data()));
  file << "K2" << k2 << "D2" << cv::Mat(1, 5, CV_64F, const_cast<double*>(rig.right.distortion.data()));
  file << "R" << r << "T" << t;
}

nlohmann::json PosesJson(const SyntheticScene& scene, const SynthOptions& options) {
  nlohmann::json poses = nlohmann::json::array();
  for (int i = 0; i < options.frames; ++i) {
    const Pose gl = scene.LeftPose(FrameTime(options, i));
    Eigen::Matrix4d cv = Eigen::Matrix4d::Identity();
    cv.topLeftCorner<3, 3>() = gl.leftCols<3>() * kFlipYz;
    cv.topRightCorner<3, 1>() = gl.col(3);
    nlohmann::json rows = nlohmann::json::array();
    for (int r = 0; r < 4; ++r) rows.push_back({cv(r, 0), cv(r, 1), cv(r, 2), cv(r, 3)});
    poses.push_back(rows);
  }
  return {{"convention", "opencv"}, {"poses", poses}};
}

// A checkerboard (kCheckerboardColumns + 1 by kCheckerboardRows + 1 squares with a white border of
// one square) at `view`'s pose in front of the left eye; the colour seen along a ray (left-eye frame).
class Checkerboard {
 public:
  explicit Checkerboard(int view) {
    PortableRandom random(StreamSeed(0xc4ec, static_cast<std::uint64_t>(view)));
    const double depth = random.Uniform(65, 110);
    // Spread over the view (its corners too, where the lens bends most), yet whole in both eyes.
    const double x = random.Uniform(-1, 1) * std::max(0.02, 0.50 - 25 / depth);
    const double y = random.Uniform(-1, 1) * std::max(0.02, 0.38 - 19 / depth);
    rotation_ = (Eigen::AngleAxisd(random.Uniform(-0.3, 0.3), Eigen::Vector3d::UnitZ()) *
                 Eigen::AngleAxisd(random.Uniform(-0.5, 0.5), Eigen::Vector3d::UnitY()) *
                 Eigen::AngleAxisd(random.Uniform(-0.5, 0.5), Eigen::Vector3d::UnitX()))
                    .toRotationMatrix();
    centre_ = depth * Eigen::Vector3d(x, y, 1);
  }

  double Grey(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction) const {
    const Eigen::Vector3d normal = rotation_.col(2);
    const double facing = normal.dot(direction);
    if (std::abs(facing) < 1e-12) return kBackground;
    const double s = normal.dot(centre_ - origin) / facing;
    if (s <= 0) return kBackground;
    const Eigen::Vector3d local = rotation_.transpose() * (origin + s * direction - centre_);
    const double a = local.x() / kCheckerboardSquare + (kCheckerboardColumns + 1) / 2.0;
    const double b = local.y() / kCheckerboardSquare + (kCheckerboardRows + 1) / 2.0;
    if (a < -1 || b < -1 || a > kCheckerboardColumns + 2 || b > kCheckerboardRows + 2) return kBackground;
    if (a < 0 || b < 0 || a >= kCheckerboardColumns + 1 || b >= kCheckerboardRows + 1) return kWhite;
    return (static_cast<int>(std::floor(a)) + static_cast<int>(std::floor(b))) % 2 == 0 ? kBlack : kWhite;
  }

 private:
  static constexpr double kBackground = 0.4, kWhite = 0.9, kBlack = 0.08;
  Eigen::Matrix3d rotation_;
  Eigen::Vector3d centre_;
};

// The board's views with 3 x 3 rays per pixel, so corners fall between pixels as in a real camera.
void WriteCheckerboard(const StereoRig& rig, int views, const fs::path& dir) {
  constexpr int kSamples = 3;
  // The board's poses are in the left eye's OpenCV frame: that frame is the world here.
  Pose left_opencv;
  left_opencv << kFlipYz, Eigen::Vector3d::Zero();
  const std::array<Pose, 2> eyes = EyePoses(rig, left_opencv);
  const std::array<std::vector<cv::Point2d>, 2> rays = {
      PixelRays(rig.left, rig.width, rig.height, kSamples),
      PixelRays(rig.right, rig.width, rig.height, kSamples)};
  const char* names[2] = {"left", "right"};
  for (const char* name : names) fs::create_directories(dir / name);
  tbb::parallel_for(0, views, [&](int view) {
    const Checkerboard board(view);
    for (int e = 0; e < 2; ++e) {
      cv::Mat grey(rig.height, rig.width, CV_8UC1);
      for (int v = 0; v < rig.height; ++v) {
        for (int u = 0; u < rig.width; ++u) {
          double sum = 0;
          for (int s = 0; s < kSamples * kSamples; ++s) {
            const cv::Point2d& ray =
                rays[e][(static_cast<std::size_t>(v) * rig.width + u) * kSamples * kSamples + s];
            sum += board.Grey(eyes[e].col(3), eyes[e].leftCols<3>() * Eigen::Vector3d(ray.x, ray.y, 1));
          }
          grey.at<std::uint8_t>(v, u) = ToByte(static_cast<float>(sum / (kSamples * kSamples)));
        }
      }
      WritePng(dir / names[e] / (FrameName(view) + ".png"), grey);
    }
  });
}

}  // namespace

StereoRig SyntheticRig(const SynthOptions& options) {
  StereoRig rig;
  rig.width = options.width;
  rig.height = options.height;
  const double w = options.width, h = options.height, f = 0.92 * w;
  rig.left.k << f, 0, 0.513 * w - 0.5, 0, 1.001 * f, 0.489 * h - 0.5, 0, 0, 1;
  rig.left.distortion = {-0.21, 0.09, 0.0012, -0.0009, 0};
  rig.right.k << 1.008 * f, 0, 0.491 * w - 0.5, 0, 1.009 * f, 0.508 * h - 0.5, 0, 0, 1;
  rig.right.distortion = {-0.19, 0.07, -0.0007, 0.001, 0};
  rig.rotation =
      Eigen::AngleAxisd(0.0115, Eigen::Vector3d(0.004, -0.009, 0.006).normalized()).toRotationMatrix();
  const Eigen::Vector3d right_centre(5.0, 0.06, -0.04);  // in the left eye's frame
  rig.translation = -rig.rotation * right_centre;
  return rig;
}

void WriteSyntheticRecording(const SyntheticScene& scene, const SynthOptions& options, const fs::path& dir) {
  const StereoRig rig = SyntheticRig(options);
  for (const char* sub : {"left", "right"}) fs::create_directories(dir / sub);
  if (options.tool) fs::create_directories(dir / "masks");
  WriteCalibration(rig, dir / "calibration.yaml");
  WriteText(dir / "poses.json", PosesJson(scene, options).dump(1) + "\n");
  constexpr int kSamples = 2;
  const std::vector<cv::Point2d> left_rays = PixelRays(rig.left, rig.width, rig.height, kSamples);
  const std::vector<cv::Point2d> right_rays = PixelRays(rig.right, rig.width, rig.height, kSamples);
  for (int i = 0; i < options.frames; ++i) {
    const double time = FrameTime(options, i);
    const SyntheticScene::State state = scene.At(time);
    const std::array<Pose, 2> eyes = EyePoses(rig, scene.LeftPose(time));
    cv::Mat left(rig.height, rig.width, CV_8UC3), right(rig.height, rig.width, CV_8UC3);
    cv::Mat tool(rig.height, rig.width, CV_8UC1);
    RenderEye(scene, state, eyes[0], left_rays, kSamples, left, &tool);
    RenderEye(scene, state, eyes[1], right_rays, kSamples, right, nullptr);
    const std::string png = FrameName(i) + ".png";
    WritePng(dir / "left" / png, left);
    WritePng(dir / "right" / png, right);
    if (options.tool) WritePng(dir / "masks" / png, tool);
  }
  if (options.checkerboard_views > 0)
    WriteCheckerboard(rig, options.checkerboard_views, dir / "checkerboard");
}

SyntheticView RenderSyntheticView(const SyntheticScene& scene, const Camera& camera, double time) {
  const SyntheticScene::State state = scene.At(time);
  const std::size_t pixels = static_cast<std::size_t>(camera.width) * camera.height;
  SyntheticView view{std::vector<float>(pixels), std::vector<float>(pixels),
                     std::vector<std::uint8_t>(pixels)};
  tbb::parallel_for(0, camera.height, [&](int v) {
    double guess = 0;
    for (int u = 0; u < camera.width; ++u) {
      Eigen::Vector3d origin, direction;
      camera.Ray(u, v, origin, direction);
      const SceneHit hit = scene.TraceAlong(state, origin, direction, guess);
      guess = hit.tissue_depth;
      const std::size_t p = static_cast<std::size_t>(v) * camera.width + u;
      view.tissue_depth[p] = static_cast<float>(hit.tissue_depth);
      view.depth[p] = static_cast<float>(hit.depth);
      view.tool[p] = hit.tool ? 1 : 0;
    }
  });
  return view;
}

}  // namespace endorecon::scene
