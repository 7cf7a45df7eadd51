#include "worker/prepare/checkerboard_calibration.h"

#include <spdlog/spdlog.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "common/error.h"
#include "worker/prepare/eye_sync.h"

namespace endorecon::prepare {
namespace {

constexpr int kMinViews = 4;

bool FindBoard(const cv::Mat& bgr, cv::Size corners, std::vector<cv::Point2f>& found) {
  cv::Mat grey;
  cv::cvtColor(bgr, grey, cv::COLOR_BGR2GRAY);
  return cv::findChessboardCornersSB(grey, corners, found,
                                     cv::CALIB_CB_NORMALIZE_IMAGE | cv::CALIB_CB_ACCURACY);
}

}  // namespace

CheckerboardCalibration CalibrateFromCheckerboard(const RecordingInput& recording,
                                                  const CheckerboardOptions& options) {
  if (options.inner_corners.width < 2 || options.inner_corners.height < 2 || !(options.square > 0) ||
      !std::isfinite(options.square)) {
    FailInvalid("the board needs at least 2x2 inner corners and a square size > 0");
  }
  // A board moved by hand: two eyes' recordings cut apart pair views of different moments, and the
  // calibration fits their motion as the rig's geometry.
  CheckEyesInStep(recording, TooShortToCheck::kQuiet);
  StereoSource source(recording);
  CheckerboardCalibration result;
  // Corners only are kept: frames are read in batches and searched in parallel.
  std::vector<std::vector<cv::Point2f>> left, right;
  int left_views = 0, right_views = 0;  // frames the board shows in in one eye, whatever the other's
  const std::size_t batch_size = 16;
  bool more = true;
  for (int index = 0; more;) {
    std::vector<StereoFrame> batch;
    while (batch.size() < batch_size && (options.frames.end < 0 || index < options.frames.end)) {
      StereoFrame frame;
      more = options.frames.Selects(index) ? source.Next(frame) : source.Skip();
      if (!more) break;
      if (options.frames.Selects(index++)) batch.push_back(std::move(frame));
    }
    if (options.frames.end >= 0 && index >= options.frames.end) more = false;
    std::vector<std::vector<cv::Point2f>> l(batch.size()), r(batch.size());
    // Each eye is searched even where the other shows no board: eyes that each find it often but
    // seldom together are views of different moments, and are said so below.
    std::vector<char> found_left(batch.size(), 0), found_right(batch.size(), 0);
    tbb::parallel_for(std::size_t{0}, 2 * batch.size(), [&](std::size_t k) {
      const std::size_t i = k / 2;
      if (k % 2 == 0)
        found_left[i] = FindBoard(batch[i].left, options.inner_corners, l[i]);
      else
        found_right[i] = FindBoard(batch[i].right, options.inner_corners, r[i]);
    });
    for (std::size_t i = 0; i < batch.size(); ++i) {
      left_views += found_left[i];
      right_views += found_right[i];
      if (!found_left[i] || !found_right[i]) continue;
      left.push_back(std::move(l[i]));
      right.push_back(std::move(r[i]));
    }
    result.frames_read += static_cast<int>(batch.size());
  }
  result.views_found = static_cast<int>(left.size());
  if (result.views_found < kMinViews) {
    const std::string board = fmt::format(
        "{}: the whole {}x{} board (inner corners) shows in both eyes in {} of {} frames", source.name(),
        options.inner_corners.width, options.inner_corners.height, result.views_found, result.frames_read);
    // Found 2026-12-07: a 96x72 rig whose left recording began a view early said only "check --board".
    // Eyes of one moment see the board in mostly the same frames.
    if (std::min(left_views, right_views) >= kMinViews &&
        2 * result.views_found < std::min(left_views, right_views)) {
      FailInvalid(fmt::format(
          "{}, though in {} of the left eye's and {} of the right eye's alone: the eyes' frames seem not to "
          "be of the same moments. If their recordings began apart, pass --skip-left or --skip-right with "
          "the frames between their starts",
          board, left_views, right_views));
    }
    FailInvalid(
        fmt::format("{} (the left eye's alone {}, the right eye's {}); at least {} are needed (check "
                    "--board, and move the board through the view)",
                    board, left_views, right_views, kMinViews));
  }
  const std::size_t views = left.size(),
                    count = std::min<std::size_t>(static_cast<std::size_t>(options.max_views), views);
  std::vector<std::size_t> used;
  for (std::size_t k = 0; k < count; ++k) used.push_back(k * views / count);
  result.views_used = static_cast<int>(used.size());

  std::vector<cv::Point3f> board;
  for (int r = 0; r < options.inner_corners.height; ++r) {
    for (int c = 0; c < options.inner_corners.width; ++c) {
      board.emplace_back(static_cast<float>(c * options.square), static_cast<float>(r * options.square), 0.f);
    }
  }
  std::vector<std::vector<cv::Point3f>> objects(used.size(), board);
  std::vector<std::vector<cv::Point2f>> left_used, right_used;
  for (std::size_t i : used) {
    left_used.push_back(left[i]);
    right_used.push_back(right[i]);
  }
  const cv::Size size = source.eye_size();
  StereoCalibration& c = result.calibration;
  cv::Mat k1, d1, k2, d2, r, t, e, f;
  std::vector<cv::Mat> rvecs, tvecs;
  const int lens = options.fit_k3 ? 0 : cv::CALIB_FIX_K3;
  result.left_rms_px = cv::calibrateCamera(objects, left_used, size, k1, d1, rvecs, tvecs, lens);
  result.right_rms_px = cv::calibrateCamera(objects, right_used, size, k2, d2, rvecs, tvecs, lens);
  result.rms_px = cv::stereoCalibrate(
      objects, left_used, right_used, k1, d1, k2, d2, size, r, t, e, f, cv::CALIB_USE_INTRINSIC_GUESS | lens,
      cv::TermCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 100, 1e-7));
  c.image_size = size;
  c.k1 = cv::Matx33d(k1);
  c.k2 = cv::Matx33d(k2);
  c.d1 = d1.reshape(1, 1);
  c.d2 = d2.reshape(1, 1);
  c.r = cv::Matx33d(r);
  c.t = cv::Vec3d(t);
  // The same views for both eyes (one eye's folder given twice) calibrate to eyes in one place, a
  // file `prepare` then refuses with a message about rectification: refused here, saying why.
  if (cv::norm(c.t) < kLeastBaselineSquares * options.square) {
    FailInvalid(source.name() + ": the two eyes calibrate to " + fmt::format("{:.3g}", cv::norm(c.t)) +
                " apart, under " + fmt::format("{:g}", kLeastBaselineSquares) +
                " of a square: are the left and right images the same eye's?");
  }
  // Each eye alone fits its views, the pair not: the views are not of one moment (a left eye's
  // recording begun a view early wrote a baseline 20 times off, warned of only as a high error).
  const double eye_rms = std::max(result.left_rms_px, result.right_rms_px);
  if (eye_rms <= kMostPlausibleRmsPx && result.rms_px > kMostPlausibleRmsPx &&
      result.rms_px > kMostPairToEyeRmsRatio * eye_rms) {
    FailInvalid(fmt::format(
        "{}: each eye calibrates well alone ({:.3g} px left, {:.3g} px right) but not the two together "
        "({:.3g} px): the eyes' views are not of the same moments. If their recordings began apart, pass "
        "--skip-left or --skip-right (the eye that began first, by the views it has before the other's "
        "first); if they are folders of pictures, check that each name pairs one moment",
        source.name(), result.left_rms_px, result.right_rms_px, result.rms_px));
  }
  // The eyes the other way round calibrate as well, the right eye on the left (T's x > 0): a file
  // `prepare` then refused (stereo_rectifier.h), written without a word (found 2026-12-07).
  if (result.rms_px <= kMostPlausibleRmsPx && c.t[0] > 0 && std::abs(c.t[0]) > std::abs(c.t[1])) {
    FailInvalid(
        fmt::format("{}: the right eye calibrates to the left of the left eye (T = ({:.4g}, {:.4g}, "
                    "{:.4g})): the eyes are given the other way round; swap --left and --right (or "
                    "the halves of the frame)",
                    source.name(), c.t[0], c.t[1], c.t[2]));
  }
  c.kind = "opencv";
  c.source = source.name();
  return result;
}

std::string CalibrationWarning(const CheckerboardCalibration& result, const CheckerboardOptions& options) {
  if (!(result.rms_px > kMostPlausibleRmsPx)) return "";
  char text[512];
  std::snprintf(
      text, sizeof(text),
      "the RMS reprojection error of %.3g px is high (a sharp, flat board calibrates well under %g px): "
      "check that --board %dx%d counts the board's inner corners (COLUMNSxROWS: a board of 10 x 7 "
      "squares has 9x6), and that the views are sharp; the baseline and focal lengths may be off",
      result.rms_px, kMostPlausibleRmsPx, options.inner_corners.width, options.inner_corners.height);
  return text;
}

}  // namespace endorecon::prepare
