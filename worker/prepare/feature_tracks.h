// Sparse correspondences between two images of the same tissue (the two eyes of a rectified
// pair, or one eye at two times): corners (Shi-Tomasi) of the first image tracked into the second
// by pyramidal Lucas-Kanade optical flow, kept only where tracking back lands where it started.
// Sub-pixel accurate, and robust to the large shifts of near tissue (pyramids of 5 levels).
#pragma once

#include <opencv2/core.hpp>
#include <vector>

namespace endorecon::prepare {

struct PointMatch {
  cv::Point2f from, to;
  int index = 0;  // of `from` among the points tracked
};

// Up to `max_corners` corners of `from` (8-bit grey) where `allowed` (8-bit, or empty for all) is
// non-zero, tracked into `to` (8-bit grey of the same size), or `at` in `from` (corners already
// chosen) when given. Matches whose forward-backward error exceeds `max_round_trip` pixels are dropped.
std::vector<PointMatch> TrackCorners(const cv::Mat& from, const cv::Mat& to, const cv::Mat& allowed,
                                     int max_corners, double max_round_trip = 0.5);
std::vector<PointMatch> TrackPoints(const cv::Mat& from, const cv::Mat& to,
                                    const std::vector<cv::Point2f>& at, double max_round_trip = 0.5);

// Positions in `to` of the points `at` of `from`, Lucas-Kanade started from `guess` (near the
// answer, e.g. a track followed over intermediate frames) on two pyramid levels; false in `found`
// where it did not converge or moved more than a pixel from the guess.
std::vector<cv::Point2f> RefineTracks(const cv::Mat& from, const cv::Mat& to,
                                      const std::vector<cv::Point2f>& at,
                                      const std::vector<cv::Point2f>& guess,
                                      std::vector<std::uint8_t>& found);

// Corners to track: Shi-Tomasi, at least `spacing` pixels apart, refined to sub-pixel positions.
std::vector<cv::Point2f> FindCorners(const cv::Mat& grey, const cv::Mat& allowed, int max_corners,
                                     double spacing);

}  // namespace endorecon::prepare
