#include "worker/prepare/feature_tracks.h"

#include <algorithm>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>

namespace endorecon::prepare {
namespace {

const cv::Size kWindow(21, 21);
constexpr int kLevels = 5;
const cv::TermCriteria kStop(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 40, 0.005);

}  // namespace

std::vector<cv::Point2f> FindCorners(const cv::Mat& grey, const cv::Mat& allowed, int max_corners,
                                     double spacing) {
  std::vector<cv::Point2f> corners;
  cv::goodFeaturesToTrack(grey, corners, max_corners, 0.005, spacing, allowed, 7);
  if (!corners.empty()) {
    cv::cornerSubPix(grey, corners, cv::Size(4, 4), cv::Size(-1, -1),
                     cv::TermCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 20, 0.01));
  }
  return corners;
}

std::vector<PointMatch> TrackPoints(const cv::Mat& from, const cv::Mat& to,
                                    const std::vector<cv::Point2f>& at, double max_round_trip) {
  if (at.empty()) return {};
  std::vector<cv::Point2f> forward, back;
  std::vector<std::uint8_t> ok_forward, ok_back;
  std::vector<float> error;
  cv::calcOpticalFlowPyrLK(from, to, at, forward, ok_forward, error, kWindow, kLevels, kStop);
  cv::calcOpticalFlowPyrLK(to, from, forward, back, ok_back, error, kWindow, kLevels, kStop);
  std::vector<PointMatch> matches;
  const cv::Rect inside(0, 0, to.cols, to.rows);
  for (std::size_t i = 0; i < at.size(); ++i) {
    if (!ok_forward[i] || !ok_back[i] || !inside.contains(forward[i])) continue;
    if (cv::norm(back[i] - at[i]) > max_round_trip) continue;
    matches.push_back({at[i], forward[i], static_cast<int>(i)});
  }
  return matches;
}

std::vector<cv::Point2f> RefineTracks(const cv::Mat& from, const cv::Mat& to,
                                      const std::vector<cv::Point2f>& at,
                                      const std::vector<cv::Point2f>& guess,
                                      std::vector<std::uint8_t>& found) {
  std::vector<cv::Point2f> refined = guess;
  std::vector<float> error;
  if (at.empty()) return refined;
  cv::calcOpticalFlowPyrLK(from, to, at, refined, found, error, kWindow, 1, kStop,
                           cv::OPTFLOW_USE_INITIAL_FLOW);
  for (std::size_t i = 0; i < at.size(); ++i) found[i] = found[i] && cv::norm(refined[i] - guess[i]) <= 1.0;
  return refined;
}

std::vector<PointMatch> TrackCorners(const cv::Mat& from, const cv::Mat& to, const cv::Mat& allowed,
                                     int max_corners, double max_round_trip) {
  const double spacing = std::max(4.0, std::sqrt(static_cast<double>(from.total()) / max_corners) / 2);
  return TrackPoints(from, to, FindCorners(from, allowed, max_corners, spacing), max_round_trip);
}

}  // namespace endorecon::prepare
