// A stereo endoscope's calibration: each eye's intrinsics and lens distortion and the pose of the
// right eye relative to the left, in OpenCV's conventions (pixel centres at integer coordinates;
// camera x right, y down, z forward). The unit of T is the clip's unit.
//
// Files read: an OpenCV stereo calibration (what cv::FileStorage writes, YAML or XML) with K1 D1 K2
// D2 R T (M1/M2 are taken for K1/K2) and optionally image_width and image_height; or a pair of ROS
// camera_info YAMLs (left, right), whose rectification and projection matrices give R and T. See
// docs/formats.md ("Stereo calibration files").
#pragma once

#include <filesystem>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace endorecon::prepare {

struct StereoCalibration {
  cv::Size image_size;  // each eye's; 0x0 when the file does not say
  cv::Matx33d k1, k2;   // camera matrices
  cv::Mat d1, d2;       // distortion (k1, k2, p1, p2[, k3[, k4, k5, k6[, ...]]]), 1 x N CV_64F
  cv::Matx33d r;        // X_right = R X_left + T
  cv::Vec3d t;
  std::string source;  // the file(s), for messages and prepare.json
  std::string kind;    // "opencv", "ros" or "rectified"

  double baseline() const { return cv::norm(t); }
};

// One file: an OpenCV stereo calibration; two: ROS camera_info YAMLs of the left and the right eye.
// Throws Error(kNotFound) for a missing file and Error(kInvalidArgument) naming the file and the
// field for anything unreadable, missing, of the wrong shape, non-finite, or not a rotation.
StereoCalibration LoadStereoCalibration(const std::vector<std::filesystem::path>& files);

// The calibration of an already rectified pair (--rectified): no distortion, no rotation, both
// eyes with focal length `focal` (pixels) and the principal point at the centre of a
// `size` image, the right eye `baseline` units to the right. Throws FailInvalid for a focal length
// or baseline that is not finite and positive.
StereoCalibration RectifiedCalibration(cv::Size size, double focal, double baseline);

// Throws FailInvalid naming the calibration when it was made for another image size than the
// recording's eyes (`eye_size`); a calibration that names no size must have its principal points
// inside the frame.
void CheckCalibrationFits(const StereoCalibration& calibration, cv::Size eye_size);

// Writes `calibration` as an OpenCV stereo calibration file (YAML or XML by the extension), with
// `extra` scalar fields (e.g. "rms_reprojection_error_px"). Throws Error(kUnavailable) when it
// cannot be written.
void WriteStereoCalibration(const std::filesystem::path& path, const StereoCalibration& calibration,
                            const std::vector<std::pair<std::string, double>>& extra = {});

}  // namespace endorecon::prepare
