// Writes the frames of a prepared clip and its layout files (docs/formats.md, "Prepared clips"):
// the EndoNeRF layout (poses_bounds.npy; masks/ with 255 = excluded) for a fixed endoscope, or
// transforms.json (per-frame poses and times; masks/ with 0 = excluded, nerfstudio's polarity)
// when it moves. Both with images_right/ and stereo.json, depth/ as float32 .npy in the
// calibration's unit (0 = unknown).
#pragma once

#include <filesystem>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "worker/prepare/stereo_rectifier.h"

namespace endorecon::prepare {

enum class ClipLayout { kEndoNerf, kTransforms };

struct PreparedFrame {
  cv::Mat left, right;  // rectified 8-bit BGR
  cv::Mat depth;        // CV_32F, 0 = unknown
  cv::Mat excluded;     // 0/255, 255 = excluded from training and metrics (tool, screen region); or empty
};

struct FramePlacement {
  cv::Matx44d pose = cv::Matx44d::eye();  // the rectified left camera's camera-to-world, OpenCV axes
  double time_s = 0;
};

class ClipWriter {
 public:
  // `masks`: whether frames carry `excluded` masks (then masks/ is written for every frame).
  ClipWriter(std::filesystem::path dir, ClipLayout layout, const RectifiedCamera& camera, bool masks);

  // Writes frame `index`'s files. Safe to call from several threads for different indices. Throws
  // Error(kUnavailable) when a file cannot be written.
  void Write(int index, const PreparedFrame& frame) const;
  // The layout file for frames 0..n-1 (their placements, in order), near/far, and stereo.json.
  void Finish(const std::vector<FramePlacement>& placements, double near, double far) const;

 private:
  std::filesystem::path dir_;
  ClipLayout layout_;
  RectifiedCamera camera_;
  bool masks_;
};

// "000042".
std::string ClipFrameName(int index);

}  // namespace endorecon::prepare
