// GCC 12 reports a false "maybe uninitialized" inside its own AVX-512 intrinsics when Eigen's
// sparse least squares is inlined here (as in background_start.cc); silenced for this file.
#if !defined(__clang__)
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif

#include "worker/engine/train/flow_start.h"

#include <Eigen/IterativeLinearSolvers>
#include <Eigen/SparseCore>
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>

#include "worker/engine/train/flow_image.h"

namespace endorecon::train {
namespace {

// Flow is computed on frames at most this wide (larger ones averaged down by a whole factor): DIS's
// cost grows with the pixels, and the grid it feeds has a few dozen cells across.
constexpr int kFlowWidth = 320;
// Flow more than this from the way back (flow pixels) is an occlusion, a highlight or a mistake.
constexpr double kRoundTripPx = 0.5;
// About this many points a frame (the grid has a few thousand vertices near the surface), and at
// most about this many in all (the least squares' cost grows with them: 367k points on a
// 160-frame clip took 11 s to start, docs/benchmarks.md).
constexpr int kPointsPerFrame = 4096;
constexpr int kPoints = 160000;
// Weight of the smoothness rows (a vertex minus each neighbour in x, y, z and time; the first knot
// minus the fixed zero at time 0), relative to the mean of the data's normal-matrix diagonal: a
// vertex without points takes its neighbours' motion. 0.003-0.05 measured alike, 0.3 worse
// (docs/benchmarks.md, "The deformation started from optical flow").
constexpr double kSmooth = 0.01;

cv::Vec2f Bilinear(const cv::Mat& field, double x, double y) {
  const int x0 = std::clamp(int(std::floor(x)), 0, field.cols - 1),
            y0 = std::clamp(int(std::floor(y)), 0, field.rows - 1);
  const int x1 = std::min(x0 + 1, field.cols - 1), y1 = std::min(y0 + 1, field.rows - 1);
  const float fx = float(std::clamp(x - x0, 0.0, 1.0)), fy = float(std::clamp(y - y0, 0.0, 1.0));
  return (field.at<cv::Vec2f>(y0, x0) * (1 - fx) + field.at<cv::Vec2f>(y0, x1) * fx) * (1 - fy) +
         (field.at<cv::Vec2f>(y1, x0) * (1 - fx) + field.at<cv::Vec2f>(y1, x1) * fx) * fy;
}

constexpr float kNone = std::numeric_limits<float>::quiet_NaN();

// Where each pixel of the reference is in the reference: itself where usable, NaN elsewhere.
cv::Mat IdentityMap(const FlowImage& ref) {
  cv::Mat map(ref.grey.size(), CV_32FC2, cv::Scalar(kNone, kNone));
  for (int y = 0; y < map.rows; ++y) {
    for (int x = 0; x < map.cols; ++x) {
      if (ref.usable.at<std::uint8_t>(y, x)) map.at<cv::Vec2f>(y, x) = cv::Vec2f(float(x), float(y));
    }
  }
  return map;
}

// Where frame f's pixels are in the reference, given the flows between f and another frame and that
// frame's map (the reference's own: IdentityMap). NaN where the flow fails its round trip, leaves
// the frame, starts on an unusable pixel, or lands where the other frame's map has none.
cv::Mat ChainStep(const FlowImage& image, const cv::Mat& back, const cv::Mat& forth,
                  const cv::Mat& previous_map) {
  cv::Mat map(previous_map.size(), CV_32FC2, cv::Scalar(kNone, kNone));
  const int w = map.cols, h = map.rows;
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      if (!image.usable.at<std::uint8_t>(y, x)) continue;
      const cv::Vec2f d = back.at<cv::Vec2f>(y, x);
      const double qx = x + d[0], qy = y + d[1];
      if (!(qx >= 0 && qy >= 0 && qx <= w - 1 && qy <= h - 1)) continue;
      const cv::Vec2f round = Bilinear(forth, qx, qy);
      if (std::hypot(d[0] + round[0], d[1] + round[1]) > kRoundTripPx) continue;
      map.at<cv::Vec2f>(y, x) = Bilinear(previous_map, qx, qy);  // NaN if any corner's chain broke
    }
  }
  return map;
}

// Where a map holds a position (not NaN), as a mask.
cv::Mat Followed(const cv::Mat& map) {
  cv::Mat channels[2];
  cv::split(map, channels);
  return channels[0] == channels[0];  // false for NaN
}

// A point the grid should carry from `pos` at `time` by `shift` (box units).
struct FlowPoint {
  std::array<double, 3> pos;
  std::array<double, 3> shift;
  double time;
};

// min |A v - shift|^2 + |S v|^2 for each axis (A the grid's weights at the points, the same for the
// three axes; S the smoothness rows), then once more with the points far off the first fit weighted
// down (Huber's weights). Returns the vertices' values (vertices x 3) and the fitted share.
Eigen::MatrixXd SolveGrid(const std::vector<FlowPoint>& points, const field::DeformationLayout& layout,
                          double* fitted) {
  const std::size_t per_slice = layout.slice / 3, side = layout.res + 1;
  const std::size_t vertices = std::size_t(layout.knots) * per_slice;
  const std::size_t n = points.size();
  // The rows, built once and scaled each round: a point's grid weights (times the square root of its
  // Huber weight), then a vertex minus each neighbour (times the smoothness weight).
  std::vector<Eigen::Triplet<double>> entries;
  entries.reserve(n * 16 + 8 * vertices);
  Eigen::MatrixXd shift(Eigen::Index(n), 3);
  for (std::size_t i = 0; i < n; ++i) {
    std::size_t vertex[16];
    double w[16];
    const int count = field::DeformWeights(layout, points[i].pos.data(), points[i].time, vertex, w);
    for (int j = 0; j < count; ++j) entries.emplace_back(Eigen::Index(i), Eigen::Index(vertex[j]), w[j]);
    for (int axis = 0; axis < 3; ++axis) shift(Eigen::Index(i), axis) = points[i].shift[axis];
  }
  Eigen::Index row = Eigen::Index(n);
  for (std::size_t v = 0; v < vertices; ++v) {
    const std::size_t slot = v % per_slice;
    const std::size_t at[3] = {slot % side, slot / side % side, slot / (side * side)};
    const std::size_t step[3] = {1, side, side * side};
    for (int a = 0; a < 3; ++a) {
      if (at[a] + 1 == side) continue;
      entries.emplace_back(row, Eigen::Index(v), 1.0);
      entries.emplace_back(row++, Eigen::Index(v + step[a]), -1.0);
    }
    // Minus the previous knot's (the fixed zero before the first).
    entries.emplace_back(row, Eigen::Index(v), 1.0);
    if (v >= per_slice) entries.emplace_back(row, Eigen::Index(v - per_slice), -1.0);
    ++row;
  }
  using Rows = Eigen::SparseMatrix<double, Eigen::RowMajor>;
  Rows unscaled(row, Eigen::Index(vertices));
  unscaled.setFromTriplets(entries.begin(), entries.end());
  entries = {};

  Eigen::VectorXd root_weight = Eigen::VectorXd::Ones(Eigen::Index(n));  // sqrt of Huber's weights
  Eigen::MatrixXd solution = Eigen::MatrixXd::Zero(Eigen::Index(vertices), 3);
  for (int round = 0; round < 2; ++round) {
    Rows a = unscaled;
    std::vector<double> diagonal(vertices, 0.0);  // of the data rows' normal matrix
    for (Eigen::Index i = 0; i < Eigen::Index(n); ++i) {
      for (Rows::InnerIterator it(a, i); it; ++it) {
        it.valueRef() *= root_weight[i];
        diagonal[std::size_t(it.col())] += it.value() * it.value();
      }
    }
    double sum = 0;
    std::size_t touched = 0;
    for (double d : diagonal) {
      sum += d;
      touched += d > 0;
    }
    const double smooth = std::sqrt(kSmooth * sum / double(std::max<std::size_t>(touched, 1)));
    for (Eigen::Index r = Eigen::Index(n); r < row; ++r) {
      for (Rows::InnerIterator it(a, r); it; ++it) it.valueRef() *= smooth;
    }
    Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(row, 3);
    rhs.topRows(Eigen::Index(n)) = root_weight.asDiagonal() * shift;
    Eigen::LeastSquaresConjugateGradient<Rows> solver;
    solver.setMaxIterations(200);
    solver.setTolerance(1e-6);
    solver.compute(a);
    for (int axis = 0; axis < 3; ++axis)
      solution.col(axis) = solver.solveWithGuess(rhs.col(axis), solution.col(axis));

    const Eigen::MatrixXd residual = (a * solution - rhs).topRows(Eigen::Index(n));
    std::vector<double> norms(n);
    double left = 0, total = 0;
    for (std::size_t i = 0; i < n; ++i) {
      const Eigen::Index r = Eigen::Index(i);
      norms[i] = residual.row(r).norm() / root_weight[r];
      left += residual.row(r).squaredNorm();
      total += rhs.row(r).squaredNorm();
    }
    *fitted = total > 0 ? 1 - left / total : 1;
    std::vector<double> sorted = norms;
    std::nth_element(sorted.begin(), sorted.begin() + std::ptrdiff_t(n / 2), sorted.end());
    const double k = 2 * sorted[n / 2];
    for (std::size_t i = 0; i < n; ++i)
      root_weight[Eigen::Index(i)] = k > 0 && norms[i] > k ? std::sqrt(k / norms[i]) : 1.0;
  }
  return solution;
}

}  // namespace

FlowStart FitDeformationToFlow(const scene::Clip& clip, const std::vector<int>& frames,
                               const scene::SceneBox& box, const field::DeformationLayout& layout,
                               float* params) {
  const auto start = std::chrono::steady_clock::now();
  FlowStart result;
  if (!clip.has_depth()) result.assumed_depth = scene::TypicalDepth(clip);
  std::vector<int> order(frames);
  std::sort(order.begin(), order.end(), [&](int a, int b) { return clip.times[a] < clip.times[b]; });
  if (order.empty() || clip.times[order.front()] != 0.0f) {
    result.skipped = "no training frame at time 0 (the canonical space)";
    return result;
  }
  const int ref = order.front();
  const int factor = (clip.width + kFlowWidth - 1) / kFlowWidth;
  const cv::Size size(clip.width / factor, clip.height / factor);
  // Frames too small for DIS (kLeastFlowSide): such a clip starts from zero.
  if (size.width < kLeastFlowSide || size.height < kLeastFlowSide) {
    result.skipped = "frames of " + std::to_string(size.width) + "x" + std::to_string(size.height) +
                     " are too small for optical flow (" + std::to_string(kLeastFlowSide) + " pixels a side)";
    return result;
  }
  const double sx = double(clip.width) / size.width, sy = double(clip.height) / size.height;
  const FlowImage ref_image = FlowImageOf(clip, ref, size, 0);
  const double ref_mean = cv::mean(ref_image.grey)[0];
  const int per_frame = std::min(kPointsPerFrame, kPoints / std::max(1, int(order.size()) - 1));
  const int stride = std::max(1, int(std::ceil(std::sqrt(double(size.area()) / std::max(1, per_frame)))));
  // A flow pixel's centre in the clip's pixels, and the clip's pixel there.
  const auto clip_x = [&](double x) { return (x + 0.5) * sx - 0.5; };
  const auto clip_y = [&](double y) { return (y + 0.5) * sy - 0.5; };
  const auto depth_at = [&](int f, double u, double v) {
    if (result.assumed_depth > 0) return float(result.assumed_depth);
    const int i = std::clamp(int(std::lround(u)), 0, clip.width - 1),
              j = std::clamp(int(std::lround(v)), 0, clip.height - 1);
    return clip.depth[f][std::size_t(j) * clip.width + i];
  };

  // Where each pixel of each training frame was at time 0, frames in time order: by the flow straight
  // to the reference where it passes its round trip, otherwise by the chain through the frame before
  // (where the previous frame's map puts the pixel moved by the flow between the two). Consecutive
  // frames move a few pixels, and the way back to time 0 can be tens, more than direct flow finds;
  // a chain alone drifts (on the real-texture clip 1.5 px from the true motion on average, the
  // direct flow where it holds 0.8 px: docs/benchmarks.md).
  const cv::Mat identity = IdentityMap(ref_image);
  cv::Mat map;  // where the previous frame's pixels were at time 0 (none before the first)
  cv::Mat previous = ref_image.grey;
  std::vector<FlowPoint> points;
  double flow_sum = 0;
  // The medium preset stops at half the flow image's resolution (finest scale 1). Going on to full
  // resolution halves the start's error against a synthetic clip's true motion and gains the
  // real-texture clip 0.17-0.36 dB; it cost the demo clip's held-out depth at 300 s (a floater at a
  // highlight) until the depth prior's holes were filled (depth_fill.h); with the fill, four demo runs
  // at 300 s scored 0.03-0.09 dB lower held out with depth 0.0053-0.0061 against 0.0051-0.0054, so it
  // stays (docs/benchmarks.md, "DIS down to the finest scale", "Holes in the depth prior filled").
  cv::Ptr<cv::DISOpticalFlow> dis = cv::DISOpticalFlow::create(cv::DISOpticalFlow::PRESET_MEDIUM);
  for (int f : order) {
    if (f == ref) continue;
    const FlowImage image = FlowImageOf(clip, f, size, ref_mean);
    cv::Mat to_ref, from_ref;
    dis->calc(image.grey, ref_image.grey, to_ref);
    dis->calc(ref_image.grey, image.grey, from_ref);
    const cv::Mat direct = ChainStep(image, to_ref, from_ref, identity);
    if (map.empty()) {
      map = direct;  // the frame before is the reference: the chain is the direct flow
    } else {
      cv::Mat back, forth;
      dis->calc(image.grey, previous, back);
      dis->calc(previous, image.grey, forth);
      map = ChainStep(image, back, forth, map);
      direct.copyTo(map, Followed(direct));  // the direct flow where it passed, the chain elsewhere
    }
    previous = image.grey;

    const std::size_t before = points.size();
    for (int y = stride / 2; y < size.height; y += stride) {
      for (int x = stride / 2; x < size.width; x += stride) {
        const cv::Vec2f q = map.at<cv::Vec2f>(y, x);
        if (std::isnan(q[0])) continue;
        const double u = clip_x(x), v = clip_y(y), u0 = clip_x(q[0]), v0 = clip_y(q[1]);
        const float z = depth_at(f, u, v), z0 = depth_at(ref, u0, v0);
        if (!(z > 0) || !(z0 > 0)) continue;
        Eigen::Vector3d origin, direction, origin0, direction0;
        clip.cameras[f].Ray(u, v, origin, direction);
        clip.cameras[ref].Ray(u0, v0, origin0, direction0);
        const Eigen::Vector3d pos = box.Normalise(origin + direction * double(z));
        const Eigen::Vector3d pos0 = box.Normalise(origin0 + direction0 * double(z0));
        if ((pos.array() < 0).any() || (pos.array() > 1).any()) continue;
        FlowPoint p;
        for (int a = 0; a < 3; ++a) {
          p.pos[a] = pos[a];
          p.shift[a] = pos0[a] - pos[a];
        }
        p.time = clip.times[f];
        points.push_back(p);
        flow_sum += std::hypot(u0 - u, v0 - v);
      }
    }
    result.frames += points.size() > before;
  }
  if (points.empty()) {
    result.skipped = "no surface point could be followed back to time 0";
    return result;
  }

  const Eigen::MatrixXd solution = SolveGrid(points, layout, &result.fitted_fraction);
  for (Eigen::Index v = 0; v < solution.rows(); ++v) {
    for (int axis = 0; axis < 3; ++axis)
      params[std::size_t(v) * 3 + std::size_t(axis)] = float(solution(v, axis));
  }
  result.points = points.size();
  result.flow_px = flow_sum / double(points.size());
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

nlohmann::json FlowStartJson(const FlowStart& start) {
  if (!start.skipped.empty()) return {{"from", "zero"}, {"why", start.skipped}};
  nlohmann::json json = {{"from", "optical flow"},
                         {"frames", start.frames},
                         {"points", start.points},
                         {"mean_flow_px", start.flow_px},
                         {"fitted_fraction", start.fitted_fraction},
                         {"seconds", start.seconds},
                         {"depth", start.assumed_depth > 0 ? "assumed" : "priors"}};
  if (start.assumed_depth > 0) json["assumed_depth"] = start.assumed_depth;
  return json;
}

}  // namespace endorecon::train
