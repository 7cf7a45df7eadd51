#include "worker/prepare/camera_rotation.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <opencv2/imgproc.hpp>

#include "worker/prepare/feature_tracks.h"
#include "worker/prepare/specular_mask.h"

namespace endorecon::prepare {
namespace {

constexpr int kMaxCorners = 400;
constexpr int kRansacRounds = 300;
constexpr int kMinInliers = 12;
constexpr double kMissPx = 2.0;  // a track the turn explains lands this close, at 640 px wide
constexpr double kRimPx = 12.0;  // corners keep this far from the view's rim, at 640 px wide
constexpr int kHighlight = 200;  // specular_mask.h's level

cv::Vec3d Ray(const cv::Matx33d& inverse_camera, cv::Point2f pixel) {
  return cv::normalize(inverse_camera * cv::Vec3d(pixel.x, pixel.y, 1.0));
}

// Where corners may be: tissue inside the view, off its rim (the rim's edge stays put as the camera
// turns) and off the highlights (they move with the light, not the tissue).
cv::Mat AllowedCorners(const cv::Mat& bgr, const cv::Mat& not_tissue, int rim) {
  cv::Mat blocked = SpecularMask(bgr, kHighlight, std::max(2, rim / 3));
  if (!not_tissue.empty()) {
    cv::Mat outside;
    cv::dilate(not_tissue, outside,
               cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(2 * rim + 1, 2 * rim + 1)));
    cv::bitwise_or(blocked, outside, blocked);
  }
  cv::Mat allowed;
  cv::bitwise_not(blocked, allowed);
  return allowed;
}

std::vector<int> Inliers(const std::vector<cv::Vec3d>& from, const std::vector<cv::Vec3d>& to,
                         const cv::Matx33d& rotation, double max_miss) {
  std::vector<int> inliers;
  for (std::size_t i = 0; i < from.size(); ++i) {
    if (cv::norm(to[i] - rotation * from[i]) <= max_miss) inliers.push_back(static_cast<int>(i));
  }
  return inliers;
}

struct Turn {
  cv::Matx33d rotation;
  std::vector<int> inliers;
};

// RANSAC over pairs of rays (a pair fixes a rotation), then the fit on the best pair's inliers and
// once more on the inliers of that fit. Seeded: the same frames give the same turns.
Turn FitTurn(const std::vector<cv::Vec3d>& from, const std::vector<cv::Vec3d>& to, double max_miss) {
  Turn best{cv::Matx33d::eye(), {}};
  if (from.size() < 2) return best;
  cv::RNG random(0x7e57);
  const int n = static_cast<int>(from.size());
  for (int round = 0; round < kRansacRounds; ++round) {
    const int a = random.uniform(0, n), b = random.uniform(0, n);
    if (a == b || cv::norm(from[a].cross(from[b])) < 1e-3) continue;
    const cv::Matx33d rotation = FitRotation({from[a], from[b]}, {to[a], to[b]});
    std::vector<int> inliers = Inliers(from, to, rotation, max_miss);
    if (inliers.size() > best.inliers.size()) best = {rotation, std::move(inliers)};
  }
  for (int refit = 0; refit < 2 && best.inliers.size() >= 2; ++refit) {
    std::vector<cv::Vec3d> f, t;
    for (int i : best.inliers) {
      f.push_back(from[i]);
      t.push_back(to[i]);
    }
    best.rotation = FitRotation(f, t);
    best.inliers = Inliers(from, to, best.rotation, max_miss);
  }
  return best;
}

double MedianMiss(const std::vector<cv::Vec3d>& from, const std::vector<cv::Vec3d>& to, const Turn& turn,
                  double focal) {
  std::vector<double> miss;
  for (int i : turn.inliers) miss.push_back(cv::norm(to[i] - turn.rotation * from[i]) * focal);
  if (miss.empty()) return 0;
  std::nth_element(miss.begin(), miss.begin() + miss.size() / 2, miss.end());
  return miss[miss.size() / 2];
}

}  // namespace

cv::Matx33d FitRotation(const std::vector<cv::Vec3d>& from, const std::vector<cv::Vec3d>& to) {
  cv::Matx33d correlation = cv::Matx33d::zeros();
  for (std::size_t i = 0; i < from.size(); ++i) correlation += to[i] * from[i].t();
  cv::Matx33d u, vt;
  cv::Matx31d w;
  cv::SVD::compute(correlation, w, u, vt);
  // A proper rotation: the smallest singular direction flips when the best orthogonal fit reflects.
  const double sign = cv::determinant(u * vt) < 0 ? -1.0 : 1.0;
  return u * cv::Matx33d::diag(cv::Vec3d(1, 1, sign)) * vt;
}

CameraTurns EstimateCameraTurns(const std::vector<cv::Mat>& frames, const cv::Matx33d& camera,
                                const cv::Mat& not_tissue) {
  CameraTurns turns;
  if (frames.empty()) return turns;
  const double scale = frames[0].cols / 640.0;
  const double focal = camera(0, 0);
  const double max_miss = kMissPx * scale / focal;
  const int rim = static_cast<int>(std::lround(std::max(3.0, kRimPx * scale)));
  const cv::Matx33d inverse_camera = camera.inv();
  // Each frame's turn from the one before it, the frames in parallel (each fit is seeded: the same
  // frames give the same turns), then chained from the first.
  const int n = static_cast<int>(frames.size());
  struct Step {
    Turn turn;
    double residual_px = 0;
  };
  std::vector<Step> steps(n);
  tbb::parallel_for(1, n, [&](int f) {
    cv::Mat previous, grey;
    cv::cvtColor(frames[f - 1], previous, cv::COLOR_BGR2GRAY);
    cv::cvtColor(frames[f], grey, cv::COLOR_BGR2GRAY);
    const auto matches =
        TrackCorners(previous, grey, AllowedCorners(frames[f - 1], not_tissue, rim), kMaxCorners);
    std::vector<cv::Vec3d> here, there;  // rays in this frame's camera, and in the previous one's
    for (const PointMatch& m : matches) {
      here.push_back(Ray(inverse_camera, m.to));
      there.push_back(Ray(inverse_camera, m.from));
    }
    steps[f].turn = FitTurn(here, there, max_miss);
    steps[f].residual_px = MedianMiss(here, there, steps[f].turn, focal);
  });
  turns.rotations.push_back(cv::Matx33d::eye());
  for (int f = 1; f < n; ++f) {
    const Step& step = steps[f];
    const bool placed = static_cast<int>(step.turn.inliers.size()) >= kMinInliers;
    if (!placed) ++turns.unplaced;
    turns.rotations.push_back(placed ? turns.rotations.back() * step.turn.rotation : turns.rotations.back());
    turns.residual_px.push_back(placed ? step.residual_px : 0.0);
    turns.inliers.push_back(placed ? static_cast<int>(step.turn.inliers.size()) : 0);
  }
  return turns;
}

}  // namespace endorecon::prepare
