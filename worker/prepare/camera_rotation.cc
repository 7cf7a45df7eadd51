// GCC 12 reports a false "maybe uninitialized" inside its own AVX-512 intrinsics when Eigen's vector
// code is inlined here (as in field/mlp.cc); the warning is located in those headers, so it is
// silenced for this file.
#if !defined(__clang__)  // clang has no such warning, and refuses to ignore an unknown one
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif

#include "worker/prepare/camera_rotation.h"

#include <tbb/parallel_for.h>

#include <Eigen/Core>
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <cmath>
#include <opencv2/calib3d.hpp>
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
// How many frames back a frame's turns are fitted: each pair a track holds across ties the chain to
// frames further back (on the real video at 5 frames/s, tracks hold up to about 6 frames).
constexpr int kGaps[] = {1, 2, 4, 8, 16};
constexpr double kHuberRadians = 3.14159265358979323846 / 180;  // AverageTurns' robust threshold
constexpr int kAveragingRounds = 20;

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

std::vector<cv::Matx33d> AverageTurns(const std::vector<PairTurn>& pairs, std::vector<cv::Matx33d> start) {
  // Gauss-Newton on the right-multiplied corrections R_k <- R_k exp(d_k), k > 0. A pair's residual is
  // e = log(turn^T R_i^T R_j); to first order it moves by d_j - (R_j^T R_i) d_i.
  std::vector<cv::Matx33d>& rotations = start;
  const int n = static_cast<int>(rotations.size());
  if (n < 2 || pairs.empty()) return rotations;
  const int unknowns = 3 * (n - 1);
  using Matrix3 = Eigen::Matrix3d;
  const auto to_eigen = [](const cv::Matx33d& m) {
    Matrix3 e;
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) e(r, c) = m(r, c);
    return e;
  };
  for (int round = 0; round < kAveragingRounds; ++round) {
    std::vector<Eigen::Triplet<double>> entries;
    Eigen::VectorXd gradient = Eigen::VectorXd::Zero(unknowns);
    const auto add_block = [&](int a, int b, const Matrix3& block) {
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) entries.emplace_back(3 * (a - 1) + r, 3 * (b - 1) + c, block(r, c));
    };
    for (const PairTurn& p : pairs) {
      if (p.i < 0 || p.j >= n || p.i == p.j) continue;
      cv::Vec3d e;
      cv::Rodrigues(p.turn.t() * rotations[p.i].t() * rotations[p.j], e);
      const double angle = cv::norm(e);
      const double w = angle <= kHuberRadians ? 1.0 : kHuberRadians / angle;
      const Eigen::Vector3d residual(e[0], e[1], e[2]);
      const Matrix3 ji = -to_eigen(rotations[p.j].t() * rotations[p.i]);
      if (p.j > 0) {
        add_block(p.j, p.j, w * Matrix3::Identity());
        gradient.segment<3>(3 * (p.j - 1)) += w * residual;
      }
      if (p.i > 0) {
        add_block(p.i, p.i, w * ji.transpose() * ji);
        gradient.segment<3>(3 * (p.i - 1)) += w * ji.transpose() * residual;
      }
      if (p.i > 0 && p.j > 0) {
        add_block(p.i, p.j, w * ji.transpose());
        add_block(p.j, p.i, w * ji);
      }
    }
    // A frame no pair reaches keeps its start; the damping also keeps the system positive definite.
    for (int k = 0; k < unknowns; ++k) entries.emplace_back(k, k, 1e-9);
    Eigen::SparseMatrix<double> normal(unknowns, unknowns);
    normal.setFromTriplets(entries.begin(), entries.end());
    const Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(normal);
    if (solver.info() != Eigen::Success) break;
    const Eigen::VectorXd step = solver.solve(-gradient);
    for (int k = 1; k < n; ++k) {
      cv::Matx33d update;
      cv::Rodrigues(cv::Vec3d(step[3 * (k - 1)], step[3 * (k - 1) + 1], step[3 * (k - 1) + 2]), update);
      rotations[k] = rotations[k] * update;
    }
    if (step.lpNorm<Eigen::Infinity>() < 1e-12) break;
  }
  return rotations;
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
  std::vector<cv::Mat> grey(frames.size()), allowed(frames.size());
  for (std::size_t f = 0; f < frames.size(); ++f) {
    cv::cvtColor(frames[f], grey[f], cv::COLOR_BGR2GRAY);
    allowed[f] = AllowedCorners(frames[f], not_tissue, rim);
  }
  // Every frame's turns from the frames kGaps before it, in parallel (each fit is seeded: the same
  // frames give the same turns).
  struct Fitted {
    int i = 0;
    cv::Matx33d turn;
    double residual_px = 0;
    int inliers = 0;
  };
  const int n = static_cast<int>(frames.size());
  std::vector<std::vector<Fitted>> fitted(n);
  tbb::parallel_for(1, n, [&](int f) {
    for (int gap : kGaps) {
      const int i = f - gap;
      if (i < 0) break;
      const auto matches = TrackCorners(grey[i], grey[f], allowed[i], kMaxCorners);
      std::vector<cv::Vec3d> here, there;  // rays in this frame's camera, and in frame i's
      for (const PointMatch& m : matches) {
        here.push_back(Ray(inverse_camera, m.to));
        there.push_back(Ray(inverse_camera, m.from));
      }
      const Turn turn = FitTurn(here, there, max_miss);
      if (static_cast<int>(turn.inliers.size()) < kMinInliers) continue;
      fitted[f].push_back(
          {i, turn.rotation, MedianMiss(here, there, turn, focal), static_cast<int>(turn.inliers.size())});
    }
  });
  // The chain from each frame's nearest fitted one is where the averaging starts.
  turns.rotations.push_back(cv::Matx33d::eye());
  std::vector<PairTurn> pairs;
  for (int f = 1; f < n; ++f) {
    for (const Fitted& t : fitted[f]) pairs.push_back({t.i, f, t.turn});
    if (fitted[f].empty()) {
      ++turns.unplaced;
      turns.rotations.push_back(turns.rotations.back());
      turns.residual_px.push_back(0);
      turns.inliers.push_back(0);
      continue;
    }
    const Fitted& nearest = fitted[f].front();
    turns.rotations.push_back(turns.rotations[nearest.i] * nearest.turn);
    turns.residual_px.push_back(nearest.residual_px);
    turns.inliers.push_back(nearest.inliers);
  }
  turns.rotations = AverageTurns(pairs, std::move(turns.rotations));
  return turns;
}

}  // namespace endorecon::prepare
