#include "worker/prepare/pose_estimator.h"

#include <algorithm>
#include <cmath>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "worker/prepare/feature_tracks.h"

namespace endorecon::prepare {
namespace {

constexpr int kCorners = 600;
constexpr int kMinInliers = 15;
constexpr double kKeepShare = 0.6;  // a new keyframe once fewer of the latest keyframe's corners are tracked
constexpr std::size_t kMaxKeyframes = 6;

// Depth at a sub-pixel position: bilinear where the four neighbours are known and agree within
// 2%, else unknown (0), so no point is lifted across a depth edge.
double DepthAt(const cv::Mat& depth, cv::Point2f p) {
  const int x = static_cast<int>(std::floor(p.x)), y = static_cast<int>(std::floor(p.y));
  if (x < 0 || y < 0 || x + 1 >= depth.cols || y + 1 >= depth.rows) return 0;
  const float a = depth.at<float>(y, x), b = depth.at<float>(y, x + 1), c = depth.at<float>(y + 1, x),
              d = depth.at<float>(y + 1, x + 1);
  const float lo = std::min({a, b, c, d}), hi = std::max({a, b, c, d});
  if (lo <= 0 || hi - lo > 0.02f * lo) return 0;
  const float fx = p.x - x, fy = p.y - y;
  return (a * (1 - fx) + b * fx) * (1 - fy) + (c * (1 - fx) + d * fx) * fy;
}

cv::Matx44d PoseFromRt(const cv::Vec3d& rvec, const cv::Vec3d& tvec) {  // world-to-camera -> camera-to-world
  cv::Matx33d r;
  cv::Rodrigues(rvec, r);
  const cv::Matx33d rt = r.t();
  const cv::Vec3d c = -(rt * tvec);
  return {rt(0, 0), rt(0, 1), rt(0, 2), c[0], rt(1, 0), rt(1, 1), rt(1, 2), c[1],
          rt(2, 0), rt(2, 1), rt(2, 2), c[2], 0,        0,        0,        1};
}

void RtFromPose(const cv::Matx44d& pose, cv::Vec3d& rvec, cv::Vec3d& tvec) {
  const cv::Matx33d r = pose.get_minor<3, 3>(0, 0).t();
  cv::Rodrigues(r, rvec);
  tvec = -(r * cv::Vec3d(pose(0, 3), pose(1, 3), pose(2, 3)));
}

}  // namespace

PoseEstimator::PoseEstimator(const cv::Matx33d& camera, cv::Size size)
    : camera_(camera), size_(size), pixel_scale_(std::max(1.0, size.width / 640.0)) {}

std::optional<PoseEstimator::Keyframe> PoseEstimator::MakeKeyframe(const cv::Mat& grey, const cv::Mat& depth,
                                                                   const cv::Mat& not_tissue,
                                                                   const cv::Matx44d& pose) const {
  cv::Mat allowed = depth > 0;
  if (!not_tissue.empty()) allowed &= not_tissue == 0;
  const double spacing = std::max(4.0, std::sqrt(static_cast<double>(grey.total()) / kCorners) / 2);
  Keyframe keyframe;
  keyframe.grey = grey;
  for (const cv::Point2f& p : FindCorners(grey, allowed, kCorners, spacing)) {
    const double z = DepthAt(depth, p);
    if (z <= 0) continue;
    const cv::Vec4d camera_point(z * (p.x - camera_(0, 2)) / camera_(0, 0),
                                 z * (p.y - camera_(1, 2)) / camera_(1, 1), z, 1);
    const cv::Vec4d world = pose * camera_point;
    keyframe.tracks.push_back({cv::Point3d(world[0], world[1], world[2]), p, p});
  }
  keyframe.corners = keyframe.tracks.size();
  if (static_cast<int>(keyframe.corners) < kMinInliers) return std::nullopt;
  return keyframe;
}

std::optional<cv::Matx44d> PoseEstimator::Add(const cv::Mat& left, const cv::Mat& depth,
                                              const cv::Mat& not_tissue) {
  cv::Mat grey;
  cv::cvtColor(left, grey, cv::COLOR_BGR2GRAY);
  if (keyframes_.empty()) {
    auto keyframe = MakeKeyframe(grey, depth, not_tissue, cv::Matx44d::eye());
    if (!keyframe) return std::nullopt;
    keyframes_.push_back(std::move(*keyframe));
    previous_ = grey;
    last_pose_ = cv::Matx44d::eye();
    return last_pose_;
  }
  // Every keyframe's corners followed from the last placed frame to this one: small steps keep
  // Lucas-Kanade unbiased by the view's change, and keyframes still in view tie the pose to the
  // first views' tissue, so it does not drift. Committed only when the frame is placed.
  std::vector<Keyframe> tracked = keyframes_;
  std::vector<cv::Point3d> points;
  std::vector<cv::Point2d> pixels;
  std::vector<std::pair<std::size_t, std::size_t>> owner;  // (keyframe, track) of each match
  for (std::size_t k = 0; k < tracked.size(); ++k) {
    std::vector<cv::Point2f> at;
    for (const Track& track : tracked[k].tracks) at.push_back(track.at);
    std::vector<Track> stepped;
    for (const PointMatch& m : TrackPoints(previous_, grey, at, 0.5 * pixel_scale_)) {
      Track track = tracked[k].tracks[static_cast<std::size_t>(m.index)];
      track.at = m.to;
      stepped.push_back(track);
    }
    std::vector<cv::Point2f> corners, guesses;
    for (const Track& track : stepped) {
      corners.push_back(track.corner);
      guesses.push_back(track.at);
    }
    std::vector<std::uint8_t> found;
    const std::vector<cv::Point2f> aligned = RefineTracks(tracked[k].grey, grey, corners, guesses, found);
    tracked[k].tracks.clear();
    for (std::size_t i = 0; i < stepped.size(); ++i) {
      if (!found[i]) continue;
      stepped[i].at = aligned[i];
      tracked[k].tracks.push_back(stepped[i]);
    }
    for (std::size_t t = 0; t < tracked[k].tracks.size(); ++t) {
      points.push_back(tracked[k].tracks[t].point);
      pixels.emplace_back(tracked[k].tracks[t].at.x, tracked[k].tracks[t].at.y);
      owner.emplace_back(k, t);
    }
  }
  if (static_cast<int>(points.size()) < kMinInliers) return std::nullopt;
  cv::Vec3d rvec, tvec;
  RtFromPose(last_pose_, rvec, tvec);
  std::vector<int> inliers;
  const bool solved = cv::solvePnPRansac(points, pixels, camera_, cv::noArray(), rvec, tvec, true, 300,
                                         static_cast<float>(1.5 * pixel_scale_), 0.999, inliers);
  if (!solved || static_cast<int>(inliers.size()) < kMinInliers) return std::nullopt;
  std::vector<cv::Point3d> inlier_points;
  std::vector<cv::Point2d> inlier_pixels;
  std::vector<std::vector<Track>> surviving(tracked.size());
  for (int i : inliers) {
    const auto [k, t] = owner[static_cast<std::size_t>(i)];
    inlier_points.push_back(points[static_cast<std::size_t>(i)]);
    inlier_pixels.push_back(pixels[static_cast<std::size_t>(i)]);
    surviving[k].push_back(tracked[k].tracks[t]);  // outliers stop being tracked
  }
  cv::solvePnPRefineLM(inlier_points, inlier_pixels, camera_, cv::noArray(), rvec, tvec);
  std::vector<cv::Point2d> projected;
  cv::projectPoints(inlier_points, rvec, tvec, camera_, cv::noArray(), projected);
  for (std::size_t i = 0; i < projected.size(); ++i)
    errors_.push_back(cv::norm(projected[i] - inlier_pixels[i]));
  last_pose_ = PoseFromRt(rvec, tvec);
  previous_ = grey;

  // Keyframes out of view are forgotten (the latest stays).
  keyframes_.clear();
  for (std::size_t k = 0; k < tracked.size(); ++k) {
    tracked[k].tracks = std::move(surviving[k]);
    if (k + 1 == tracked.size() || static_cast<int>(tracked[k].tracks.size()) >= kMinInliers) {
      keyframes_.push_back(std::move(tracked[k]));
    }
  }
  if (static_cast<double>(keyframes_.back().tracks.size()) < kKeepShare * keyframes_.back().corners) {
    if (auto keyframe = MakeKeyframe(grey, depth, not_tissue, last_pose_)) {
      keyframes_.push_back(std::move(*keyframe));
      // At most kMaxKeyframes: the one with the fewest tracks left goes (never the first nor the newest).
      if (keyframes_.size() > kMaxKeyframes) {
        const auto fewest = std::min_element(
            keyframes_.begin() + 1, keyframes_.end() - 1,
            [](const Keyframe& a, const Keyframe& b) { return a.tracks.size() < b.tracks.size(); });
        keyframes_.erase(fewest);
      }
    }
  }
  return last_pose_;
}

}  // namespace endorecon::prepare
