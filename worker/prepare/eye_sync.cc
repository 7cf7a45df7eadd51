#include "worker/prepare/eye_sync.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "common/error.h"

namespace endorecon::prepare {
namespace {

// Both eyes of a rig see one scene move; their signals matched at 0.99 in step on the real
// laparoscopic video (its right eye made by a shift, each eye with noise of its own) and at 0.9 on
// the synthetic recording. A lag is said only where the match is strong and the frames as given match
// clearly worse: a scene moving evenly (breathing alone) matches well at many lags, as given too.
constexpr double kClearMatch = 0.6;
constexpr double kClearMargin = 0.25;
constexpr int kMinSamples = 40;
// A lag is one only where no other peak, further than kNearLags from it, matches within kClearRival
// of it: a rhythm (breathing) matches as well a period away, and which period is not known.
constexpr int kNearLags = 2;
constexpr double kClearRival = 0.1;
// Lags that match within this of the best are not told from it.
constexpr double kPeakTolerance = 0.03;
// A sharp peak (its neighbours more than kPeakTolerance below) this strong is a lag even when the
// frames as given match only this much worse: a frame's lag on the real video (1.00 against 0.85).
constexpr double kSharpMatch = 0.9;
constexpr double kSharpMargin = 0.1;

// "--skip-left 3", "--skip-left 3 and --skip-right 1": the skips that are not 0.
std::string SkipsText(int skip_left, int skip_right) {
  std::string text = skip_left > 0 ? fmt::format("--skip-left {}", skip_left) : "";
  if (skip_right > 0) text += (text.empty() ? "" : " and ") + fmt::format("--skip-right {}", skip_right);
  return text;
}

}  // namespace

bool EyeLag::OutOfStep() const {
  if (frames == 0 || samples < kMinSamples || match < kClearMatch || match_elsewhere > match - kClearRival)
    return false;
  // A peak clearly above the frames as given, or a sharp and strong one (no lag beside it within
  // kPeakTolerance) above them by less: on the real video a skip one frame off matched 1.00 there
  // and 0.85 as given, and passed (found 2026-12-07).
  return match_in_step <= match - kClearMargin ||
         (earliest == latest && match >= kSharpMatch && match_in_step <= match - kSharpMargin);
}

cv::Mat FrameChange(const cv::Mat& frame, cv::Mat& previous) {
  constexpr int kWidth = 64;
  cv::Mat grey, small;
  cv::cvtColor(frame, grey, cv::COLOR_BGR2GRAY);
  const int width = std::min(kWidth, grey.cols);
  const int height = std::max(kBands, static_cast<int>(std::lround(double(grey.rows) * width / grey.cols)));
  cv::resize(grey, small, cv::Size(width, height), 0, 0, cv::INTER_AREA);
  small.convertTo(small, CV_32F);
  cv::Mat change(kBands, 1, CV_32F, cv::Scalar(0));
  if (!previous.empty()) {
    const cv::Mat difference = cv::abs(small - previous);
    for (int band = 0; band < kBands; ++band) {
      const int top = band * height / kBands, bottom = (band + 1) * height / kBands;
      change.at<float>(band) = static_cast<float>(cv::mean(difference.rowRange(top, bottom))[0]);
    }
  }
  previous = small;
  return change;
}

EyeLag MatchLag(const cv::Mat& left, const cv::Mat& right, int max_lag) {
  // Compared as departures from their own second-long average: motion that drifts slowly matches
  // nearly as well a few frames off (the synthetic recording's was read 6 frames out for 7), and
  // its frame-to-frame differences are mostly the cameras' noise (which no two eyes share). Three
  // frames averaged against 25, in frames: a rate near 25 fps is assumed.
  const auto departures = [](const cv::Mat& signal) {
    cv::Mat near, around;
    if (signal.empty()) return signal;
    cv::blur(signal, near, cv::Size(3, 1), cv::Point(-1, -1), cv::BORDER_REPLICATE);
    cv::blur(signal, around, cv::Size(25, 1), cv::Point(-1, -1), cv::BORDER_REPLICATE);
    return cv::Mat(near - around);
  };
  const cv::Mat a = departures(left), b = departures(right);
  EyeLag best;
  const int length = std::min(a.cols, b.cols) - 2 * max_lag;  // the right eye's middle, slid over the left
  if (max_lag < 0 || length < 2 || a.rows != b.rows) return best;
  const cv::Mat middle = b(cv::Rect(max_lag, 0, length, b.rows));
  if (cv::Scalar mean, deviation; cv::meanStdDev(middle, mean, deviation), deviation[0] == 0) return best;
  // Pearson's correlation at every lag: matches[k] is left[i + k - max_lag] against right[i].
  cv::Mat matches;
  cv::matchTemplate(a(cv::Rect(0, 0, length + 2 * max_lag, a.rows)), middle, matches, cv::TM_CCOEFF_NORMED);
  cv::Point at;
  cv::minMaxLoc(matches, nullptr, &best.match, nullptr, &at);
  best.frames = at.x - max_lag;
  best.samples = length;
  best.match_in_step = matches.at<float>(max_lag);
  const auto close = [&](int k) { return matches.at<float>(k) >= best.match - kPeakTolerance; };
  int earliest = at.x, latest = at.x;
  while (earliest > 0 && close(earliest - 1)) --earliest;
  while (latest + 1 < matches.cols && close(latest + 1)) ++latest;
  best.earliest = earliest - max_lag;
  best.latest = latest - max_lag;
  // The best other peak: a rhythm's next period.
  best.match_elsewhere = -1;
  for (int k = 1; k + 1 < matches.cols; ++k) {
    const float m = matches.at<float>(k);
    if (m >= matches.at<float>(k - 1) && m >= matches.at<float>(k + 1) && std::abs(k - at.x) > kNearLags)
      best.match_elsewhere = std::max<double>(best.match_elsewhere, m);
  }
  return best;
}

void CheckEyesInStep(const RecordingInput& input, TooShortToCheck too_short) {
  if (input.layout != StereoLayout::kTwoSources) return;
  // Two folders of different lengths are read as far as the shorter: cut apart, they usually differ,
  // and their lag is what to say (the preparation refuses them after, when they are in step).
  StereoSource source(input, StereoSource::UnequalLengths::kRead);
  std::vector<cv::Mat> left, right;  // a column per frame
  cv::Mat previous_left, previous_right;
  StereoFrame frame;
  // Not past the shorter eye's announced end: reaching it is warned of once, by the preparation.
  const int announced = source.announced_frames();
  const int limit = announced > 0 ? std::min(kSyncFrames, announced) : kSyncFrames;
  int pairs = 0;
  for (; pairs < limit && source.Next(frame); ++pairs) {
    cv::Mat a = FrameChange(frame.left, previous_left), b = FrameChange(frame.right, previous_right);
    if (pairs == 0) continue;  // no change before the first frame
    left.push_back(a);
    right.push_back(b);
  }
  // Nothing is left after the skips: said here, where the skips are known, not as "no point matched"
  // or "no frame selected" later (found 2026-12-07).
  if (pairs == 0 && (input.skip_left > 0 || input.skip_right > 0)) {
    FailInvalid(fmt::format("{}: no pair of frames is left after {}", source.name(),
                            SkipsText(input.skip_left, input.skip_right)));
  }
  if (pairs == 0) return;
  EyeLag lag;
  if (!left.empty()) {
    cv::Mat left_signal, right_signal;
    cv::hconcat(left, left_signal);
    cv::hconcat(right, right_signal);
    lag = MatchLag(left_signal, right_signal, left_signal.cols / 4);
    spdlog::debug("{}: the eyes' motion matches {:.2f} as given, best {:.2f} at a lag of {} frame(s)",
                  source.name(), lag.match_in_step, lag.match, lag.frames);
  }
  // A quarter of the signal each way is searched: what is compared is its middle half.
  if (const int changes = static_cast<int>(left.size()); changes - 2 * (changes / 4) < kMinSamples) {
    // A short clip: a lag of a few frames would pass unseen (found 2026-12-07).
    if (too_short == TooShortToCheck::kQuiet) return;
    spdlog::warn(
        "{}: {} pair(s) are too few to check that the eyes' recordings begin together (about {} are "
        "needed); if they were cut at different moments, pass --skip-left or --skip-right "
        "(docs/formats.md, \"Raw recordings\")",
        source.name(), changes + 1, 2 * kMinSamples);
    return;
  }
  if (!lag.OutOfStep()) return;
  const bool left_first = lag.frames > 0;
  const char* first = left_first ? "left" : "right";
  const char* second = left_first ? "right" : "left";
  const int frames = std::abs(lag.frames);
  // A scene that moves smoothly tells the lag to within a frame or two only: the range is said.
  const std::string apart =
      lag.earliest == lag.latest
          ? fmt::format("{} frame(s) apart", frames)
          : fmt::format(
                "about {} frame(s) apart (between {} and {}: the scene moves too smoothly here to tell "
                "the frame)",
                frames, std::min(std::abs(lag.earliest), std::abs(lag.latest)),
                std::max(std::abs(lag.earliest), std::abs(lag.latest)));
  // The advice counts from the files' first frames: skips given already are added in, so following
  // it twice cannot swing between two values (found 2026-12-07).
  const bool skipped = input.skip_left > 0 || input.skip_right > 0;
  const int needed = input.skip_left - input.skip_right + lag.frames;  // > 0: the left eye's to drop
  const std::string given = SkipsText(input.skip_left, input.skip_right);
  const std::string pass =
      needed == 0
          ? fmt::format("Leave out {}: the files begin together", given)
          : fmt::format("Pass {} to drop the {} eye's first {} frame(s) and pair the rest{}",
                        SkipsText(std::max(needed, 0), std::max(-needed, 0)), needed > 0 ? "left" : "right",
                        std::abs(needed), skipped ? " instead of " + given : "");
  FailInvalid(fmt::format(
      "{}: the eyes' recordings{} begin {}: what the {} eye sees move matches what the {} eye sees "
      "{} frame(s) later (correlation {:.2f} over {} frames; {:.2f} as the frames are paired now), so the "
      "{} eye's recording began first. {} (docs/formats.md, \"Raw recordings\")",
      source.name(), skipped ? " after " + given : "", apart, second, first, frames, lag.match, lag.samples,
      lag.match_in_step, first, pass));
}

}  // namespace endorecon::prepare
