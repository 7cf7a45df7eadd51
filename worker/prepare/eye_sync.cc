#include "worker/prepare/eye_sync.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "common/error.h"

namespace endorecon::prepare {
namespace {

// Both eyes of a rig see one scene move; their signals matched at 0.9 or more in step on the real
// laparoscopic video. A lag is said only where the match is strong and the frames as given match
// clearly worse: a scene moving evenly (breathing alone) matches well at many lags, as given too.
constexpr double kClearMatch = 0.6;
constexpr double kClearMargin = 0.25;
constexpr int kMinSamples = 40;
// A lag is one only where no other peak, further than kNearLags from it, matches within kClearRival
// of it: a rhythm (breathing) matches as well a period away, and which period is not known.
constexpr int kNearLags = 2;
constexpr double kClearRival = 0.1;

}  // namespace

bool EyeLag::OutOfStep() const {
  return frames != 0 && samples >= kMinSamples && match >= kClearMatch &&
         match_in_step <= match - kClearMargin && match_elsewhere <= match - kClearRival;
}

double FrameChange(const cv::Mat& frame, cv::Mat& previous) {
  constexpr int kWidth = 64;
  cv::Mat grey, small;
  cv::cvtColor(frame, grey, cv::COLOR_BGR2GRAY);
  const int width = std::min(kWidth, grey.cols);
  const int height = std::max(1, static_cast<int>(std::lround(double(grey.rows) * width / grey.cols)));
  cv::resize(grey, small, cv::Size(width, height), 0, 0, cv::INTER_AREA);
  small.convertTo(small, CV_32F);
  const double change = previous.empty() ? 0 : cv::norm(small, previous, cv::NORM_L1) / double(small.total());
  previous = small;
  return change;
}

EyeLag MatchLag(const std::vector<double>& left, const std::vector<double>& right, int max_lag) {
  // Compared as changes from one sample to the next: motion that speeds up and slows down slowly
  // matches nearly as well a few frames off, its changes do not.
  const auto changes = [](const std::vector<double>& signal) {
    cv::Mat out(1, std::max<int>(0, static_cast<int>(signal.size()) - 1), CV_32F);
    for (int i = 0; i < out.cols; ++i) out.at<float>(i) = static_cast<float>(signal[i + 1] - signal[i]);
    return out;
  };
  const cv::Mat a = changes(left), b = changes(right);
  EyeLag best;
  const int length = std::min(a.cols, b.cols) - 2 * max_lag;  // the right eye's middle, slid over the left
  if (max_lag < 0 || length < 2) return best;
  const cv::Mat middle = b(cv::Rect(max_lag, 0, length, 1));
  if (cv::Scalar mean, deviation; cv::meanStdDev(middle, mean, deviation), deviation[0] == 0) return best;
  // Pearson's correlation at every lag: matches[k] is left[i + k - max_lag] against right[i].
  cv::Mat matches;
  cv::matchTemplate(a(cv::Rect(0, 0, length + 2 * max_lag, 1)), middle, matches, cv::TM_CCOEFF_NORMED);
  cv::Point at;
  cv::minMaxLoc(matches, nullptr, &best.match, nullptr, &at);
  best.frames = at.x - max_lag;
  best.samples = length;
  best.match_in_step = matches.at<float>(max_lag);
  // The best other peak: a rhythm's next period.
  best.match_elsewhere = -1;
  for (int k = 1; k + 1 < matches.cols; ++k) {
    const float m = matches.at<float>(k);
    if (m >= matches.at<float>(k - 1) && m >= matches.at<float>(k + 1) && std::abs(k - at.x) > kNearLags)
      best.match_elsewhere = std::max<double>(best.match_elsewhere, m);
  }
  return best;
}

void CheckEyesInStep(const RecordingInput& input) {
  if (input.layout != StereoLayout::kTwoSources) return;
  StereoSource source(input);
  std::vector<double> left, right;
  cv::Mat previous_left, previous_right;
  StereoFrame frame;
  // Not past the shorter eye's announced end: reaching it is warned of once, by the preparation.
  const int announced = source.announced_frames();
  const int limit = announced > 0 ? std::min(kSyncFrames, announced) : kSyncFrames;
  for (int i = 0; i < limit && source.Next(frame); ++i) {
    const double a = FrameChange(frame.left, previous_left), b = FrameChange(frame.right, previous_right);
    if (i == 0) continue;  // no change before the first frame
    left.push_back(a);
    right.push_back(b);
  }
  const EyeLag lag = MatchLag(left, right, static_cast<int>(left.size()) / 4);
  spdlog::debug("{}: the eyes' motion matches {:.2f} as given, best {:.2f} at a lag of {} frame(s)",
                source.name(), lag.match_in_step, lag.match, lag.frames);
  if (!lag.OutOfStep()) return;
  const bool left_first = lag.frames > 0;
  const int frames = std::abs(lag.frames);
  FailInvalid(fmt::format(
      "{}: the eyes' recordings begin {} frame(s) apart: what the {} eye sees move matches what the {} eye "
      "sees {} frame(s) later (correlation {:.2f} over {} frames; {:.2f} as the frames are paired now), so "
      "the {} eye's recording began first. Pass --skip-{} {} to drop its first {} frame(s) and pair the "
      "rest (docs/formats.md, \"Raw recordings\")",
      source.name(), frames, left_first ? "right" : "left", left_first ? "left" : "right", frames, lag.match,
      lag.samples, lag.match_in_step, left_first ? "left" : "right", left_first ? "left" : "right", frames,
      frames));
}

}  // namespace endorecon::prepare
