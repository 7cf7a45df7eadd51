// What sparse matches between rectified eyes say about a recording, before any dense matching:
// the disparities present (which sets the range SGBM searches) and how far matched points lie off
// the same row (the rectification's epipolar error, a check of the calibration).
#pragma once

#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "worker/prepare/stereo_depth.h"

namespace endorecon::prepare {

struct ErrorStats {
  double median = 0, rms = 0, p95 = 0;
  int count = 0;
};

struct StereoSurvey {
  int frames = 0;                     // pairs surveyed
  int same_picture = 0;               // of them, eyes showing one picture (under a grey level apart, and
                                      // under a tenth of the picture's own spread)
  std::vector<float> disparities;     // x_left - x_right of the matches on the same row
  std::vector<float> vertical;        // y_right - y_left of every match
  ErrorStats epipolar_error() const;  // of |vertical|
  // The range SGBM searches: the 1st to 99th percentile of the disparities, widened by a quarter
  // of their span and 8 pixels each way, at least 0, rounded out to a multiple of 16 wide; its
  // floor 0.8 x the 1st percentile. Without matches: [0, width / 4), floor 0.5.
  DisparityRange Range(int width) const;
  // Throws FailInvalid naming `recording` when the disparities say the eyes are swapped: most of them
  // negative (below -1 px), of kEyeOrderMatches matches or more. Swapped eyes prepared a clip with a
  // third of its pixels' depth, and that a third too far, without a word (found 2026-12-06).
  void CheckEyeOrder(const std::string& recording) const;
  // Throws FailInvalid naming `recording` when every pair surveyed shows one picture twice (a mono
  // recording given as stereo: it read as swapped eyes, or prepared 0% depth; found 2026-12-06).
  void CheckTwoViews(const std::string& recording) const;
  static constexpr std::size_t kEyeOrderMatches = 20;
};

// Counts one raw pair (8-bit BGR, before rectification) in `survey`: whether its eyes show one
// picture (CheckTwoViews).
void SurveyRawPair(const cv::Mat& left, const cv::Mat& right, StereoSurvey& survey);

// Adds the matches of one rectified pair (8-bit BGR) to `survey`: up to `max_corners` corners of
// the left eye where `allowed` (0/255 or empty) is set, tracked into the right eye.
void SurveyPair(const cv::Mat& left, const cv::Mat& right, const cv::Mat& allowed, StereoSurvey& survey,
                int max_corners = 400);

ErrorStats Summarise(std::vector<double> values);  // of the absolute values

}  // namespace endorecon::prepare
