// A moving endoscope's poses from its own rectified stereo frames. Keyframes carry corners on
// tissue (never on tools, excluded regions or highlights) lifted to 3D by their stereo depth; the
// corners of every keyframe still in view (up to six) are followed from frame to frame
// (Lucas-Kanade) and re-aligned with the keyframe's own image there (so the small errors of each
// step do not add up), each frame solves PnP with RANSAC on those 3D-2D matches and refines the
// pose on the inliers (Levenberg-Marquardt); outliers stop being followed.
// A frame becomes a keyframe when it keeps too few of the latest keyframe's corners. A frame that
// cannot be placed (too few inliers) gets no pose; the caller drops it.
#pragma once

#include <opencv2/core.hpp>
#include <optional>
#include <vector>

#include "worker/prepare/stereo_survey.h"

namespace endorecon::prepare {

class PoseEstimator {
 public:
  // `camera`: the rectified left camera's matrix (OpenCV pixel convention); no distortion.
  PoseEstimator(const cv::Matx33d& camera, cv::Size size);

  // The next frame, in time order: rectified left image (8-bit BGR), its depth (CV_32F, 0 =
  // unknown) and the pixels that are not tissue (0/255: tools, excluded regions; or empty).
  // Returns the camera-to-world pose (OpenCV axes; the first frame placed is the world), or
  // nothing when the frame cannot be placed.
  std::optional<cv::Matx44d> Add(const cv::Mat& left, const cv::Mat& depth, const cv::Mat& not_tissue);

  // The inliers' reprojection error over every placed frame after the first, in pixels.
  ErrorStats reprojection_error() const { return Summarise(errors_); }

 private:
  struct Track {
    cv::Point3d point;   // a keyframe corner's world position
    cv::Point2f corner;  // where it is in its keyframe
    cv::Point2f at;      // where it is in the last placed frame
  };
  struct Keyframe {
    cv::Mat grey;
    std::vector<Track> tracks;  // its corners still followed
    std::size_t corners = 0;    // how many it started with
  };
  std::optional<Keyframe> MakeKeyframe(const cv::Mat& grey, const cv::Mat& depth, const cv::Mat& not_tissue,
                                       const cv::Matx44d& pose) const;

  cv::Matx33d camera_;
  cv::Size size_;
  double pixel_scale_;               // thresholds are set for 640-pixel-wide frames
  std::vector<Keyframe> keyframes_;  // oldest first
  cv::Mat previous_;                 // the last placed frame (grey)
  cv::Matx44d last_pose_ = cv::Matx44d::eye();
  std::vector<double> errors_;
};

}  // namespace endorecon::prepare
