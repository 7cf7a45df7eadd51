// A mono endoscope's turning, from its own frames. A laparoscope pivots at its port; seen from its
// tip, over a few frames that motion is mostly a turn, and a mono recording has no depth to place a
// translation with (nor parallax enough: on the real video in ../shared/data/real/ the essential
// matrix between neighbouring frames is ill-posed while a homography fits most tracks). So each
// frame's camera is the previous one turned: corners on tissue (inside the scope's view, not on
// highlights) are followed into the frame (Lucas-Kanade, feature_tracks.h), and the rotation that
// carries one frame's viewing rays onto the other's is fitted robustly (RANSAC over pairs of rays,
// then least squares on the inliers). Turns are fitted between each frame and the frames 1, 2, 4, 8
// and 16 before it, where their tracks hold, and every frame's turn is the one that agrees best with
// all of them (rotation averaging, started from the chain of neighbours): a chain alone drifts, by
// 1-2 degrees over 5 s on the real video (docs/benchmarks.md). The first frame is the world.
#pragma once

#include <opencv2/core.hpp>
#include <vector>

namespace endorecon::prepare {

struct CameraTurns {
  std::vector<cv::Matx33d> rotations;  // per frame, camera-to-world (OpenCV axes); [0] = identity
  // Per frame after the first, of its turn from the nearest earlier frame it was fitted to: the
  // inliers' median miss (pixels) and the tracks the turn explains (0: no earlier frame fitted).
  std::vector<double> residual_px;
  std::vector<int> inliers;
  int unplaced = 0;  // frames no turn from an earlier frame could be fitted to: they keep the last one
};

// A turn fitted between two frames i < j: rays of frame j carried into frame i's camera
// (rotation_j = rotation_i * turn, camera-to-world).
struct PairTurn {
  int i = 0, j = 0;
  cv::Matx33d turn = cv::Matx33d::eye();
};

// The rotations (camera-to-world, [0] fixed) that best agree with `pairs`: least squares on the
// turns' angle errors, robust to a few wrong pairs (Huber beyond a degree), by Gauss-Newton from
// `start`. A frame no pair reaches keeps its start.
std::vector<cv::Matx33d> AverageTurns(const std::vector<PairTurn>& pairs, std::vector<cv::Matx33d> start);

// `frames`: 8-bit BGR, one size, in time order. `camera`: their pixel camera matrix (OpenCV
// convention). `not_tissue`: 8-bit, non-zero where no frame shows tissue (outside the view), or empty.
CameraTurns EstimateCameraTurns(const std::vector<cv::Mat>& frames, const cv::Matx33d& camera,
                                const cv::Mat& not_tissue);

// The rotation R that best carries the unit rays `from` onto `to` (to ~ R from), least squares
// (Wahba's problem, by SVD); at least two rays that are not parallel.
cv::Matx33d FitRotation(const std::vector<cv::Vec3d>& from, const std::vector<cv::Vec3d>& to);

}  // namespace endorecon::prepare
