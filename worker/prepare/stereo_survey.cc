#include "worker/prepare/stereo_survey.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "common/error.h"
#include "worker/prepare/feature_tracks.h"

namespace endorecon::prepare {
namespace {

double Percentile(std::vector<float> values, double p) {
  const auto k = static_cast<std::size_t>(std::clamp(p, 0.0, 1.0) * (values.size() - 1));
  std::nth_element(values.begin(), values.begin() + static_cast<long>(k), values.end());
  return values[k];
}

}  // namespace

ErrorStats Summarise(std::vector<double> values) {
  ErrorStats stats;
  if (values.empty()) return stats;
  double squares = 0;
  for (double& v : values) {
    v = std::abs(v);
    squares += v * v;
  }
  std::sort(values.begin(), values.end());
  stats.count = static_cast<int>(values.size());
  stats.median = values[values.size() / 2];
  stats.p95 = values[static_cast<std::size_t>(0.95 * (values.size() - 1))];
  stats.rms = std::sqrt(squares / values.size());
  return stats;
}

ErrorStats StereoSurvey::epipolar_error() const { return Summarise({vertical.begin(), vertical.end()}); }

DisparityRange StereoSurvey::Range(int width) const {
  if (disparities.size() < 8) return {0, std::max(16, (width / 4 + 15) / 16 * 16), 0.5};
  const double lo = Percentile(disparities, 0.01), hi = Percentile(disparities, 0.99);
  const double margin = 0.25 * (hi - lo) + 8;
  const int min = std::max(0, static_cast<int>(std::floor(lo - margin)));
  const int max = static_cast<int>(std::ceil(hi + margin));
  return {min, std::max(16, (max - min + 15) / 16 * 16), std::max({static_cast<double>(min), 0.8 * lo, 0.5})};
}

void StereoSurvey::CheckTwoViews(const std::string& recording) const {
  if (frames > 0 && same_picture == frames) {
    FailInvalid(
        recording + ": the two eyes show the same picture (under a grey level apart on average in " +
        "each of the " + std::to_string(frames) +
        " pairs surveyed): a mono recording given as stereo, or a scene too far for the eyes to see it "
        "apart? " +
        "Depth needs each eye's own view; a mono video is reconstructed as a recording of one eye " +
        "(`endorecon-worker to-dicom VIDEO -o REC.dcm`, then reconstruct or submit REC.dcm)");
  }
}

void StereoSurvey::CheckEyeOrder(const std::string& recording) const {
  if (disparities.size() < kEyeOrderMatches) return;
  const double median = Percentile(disparities, 0.5);
  if (median < -1) {
    FailInvalid(recording + ": the points of the left eye lie further left in the right eye (a median " +
                "disparity of " + std::to_string(median) + " px over " + std::to_string(disparities.size()) +
                " matches; a right eye on the right sees them further right): the eyes are given the other " +
                "way round (swap --left and --right, or the halves of the frame; if the other way gives this "
                "too, the calibration is not this rig's)");
  }
}

void SurveyRawPair(const cv::Mat& left, const cv::Mat& right, StereoSurvey& survey) {
  // One picture: under a grey level apart on average, and under a tenth of how much the picture
  // itself varies (two views of a dark scene differ little as well, yet differ as much as the scene
  // does).
  const double apart = cv::norm(left, right, cv::NORM_L1) / (double(left.total()) * left.channels());
  cv::Scalar mean, deviation;
  cv::meanStdDev(left, mean, deviation);
  const double varies = (deviation[0] + deviation[1] + deviation[2]) / 3;
  ++survey.frames;
  survey.same_picture += apart < 1 && apart < 0.1 * varies;
}

void SurveyPair(const cv::Mat& left, const cv::Mat& right, const cv::Mat& allowed, StereoSurvey& survey,
                int max_corners) {
  cv::Mat left_grey, right_grey;
  cv::cvtColor(left, left_grey, cv::COLOR_BGR2GRAY);
  cv::cvtColor(right, right_grey, cv::COLOR_BGR2GRAY);
  for (const PointMatch& m : TrackCorners(left_grey, right_grey, allowed, max_corners)) {
    const float dy = m.to.y - m.from.y;
    survey.vertical.push_back(dy);
    // Matches far off the row are mismatches whatever the rectification; they say nothing of depth.
    if (std::abs(dy) < 2 + 0.01 * left.rows) survey.disparities.push_back(m.from.x - m.to.x);
  }
}

}  // namespace endorecon::prepare
