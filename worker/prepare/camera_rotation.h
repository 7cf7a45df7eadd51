// A mono endoscope's turning, from its own frames. A laparoscope pivots at its port; seen from its
// tip, over a few frames that motion is mostly a turn, and a mono recording has no depth to place a
// translation with (nor parallax enough: on the real video in ../shared/data/real/ the essential
// matrix between neighbouring frames is ill-posed while a homography fits most tracks). So each
// frame's camera is the previous one turned: corners on tissue (inside the scope's view, not on
// highlights) are followed into the frame (Lucas-Kanade, feature_tracks.h), and the rotation that
// carries one frame's viewing rays onto the other's is fitted robustly (RANSAC over pairs of rays,
// then least squares on the inliers). The turns are chained; the first frame is the world.
#pragma once

#include <opencv2/core.hpp>
#include <vector>

namespace endorecon::prepare {

struct CameraTurns {
  std::vector<cv::Matx33d> rotations;  // per frame, camera-to-world (OpenCV axes); [0] = identity
  std::vector<double> residual_px;     // per frame after the first: the inliers' median miss, pixels
  std::vector<int> inliers;            // per frame after the first: tracks the turn explains
  int unplaced = 0;                    // frames whose turn could not be fitted: they keep the last one
};

// `frames`: 8-bit BGR, one size, in time order. `camera`: their pixel camera matrix (OpenCV
// convention). `not_tissue`: 8-bit, non-zero where no frame shows tissue (outside the view), or empty.
CameraTurns EstimateCameraTurns(const std::vector<cv::Mat>& frames, const cv::Matx33d& camera,
                                const cv::Mat& not_tissue);

// The rotation R that best carries the unit rays `from` onto `to` (to ~ R from), least squares
// (Wahba's problem, by SVD); at least two rays that are not parallel.
cv::Matx33d FitRotation(const std::vector<cv::Vec3d>& from, const std::vector<cv::Vec3d>& to);

}  // namespace endorecon::prepare
