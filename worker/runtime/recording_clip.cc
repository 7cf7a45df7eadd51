#include "worker/runtime/recording_clip.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "common/dicom/recording_header.h"
#include "common/dicom_file.h"
#include "common/error.h"
#include "common/file_write.h"
#include "common/npy.h"
#include "worker/engine/eval/exports.h"
#include "worker/engine/scene/endonerf_loader.h"
#include "worker/engine/scene/outside_view.h"
#include "worker/engine/train/train_config.h"
#include "worker/prepare/camera_rotation.h"
#include "worker/prepare/prepare_clip.h"

namespace endorecon::worker {
namespace fs = std::filesystem;
namespace {

// EndoNeRF's field of view (f = 569.468 px at 640 px), the synthetic clips' too.
constexpr double kFocalPerWidth = 0.8898;
constexpr double kNear = 40, kFar = 130;

void WriteFrames(const std::vector<cv::Mat>& frames, const fs::path& folder) {
  fs::create_directories(folder);
  for (std::size_t i = 0; i < frames.size(); ++i) {
    const fs::path path = folder / eval::FrameFileName(static_cast<int>(i), ".png");
    if (!cv::imwrite(path.string(), frames[i]))
      Fail(ErrorCode::kUnavailable, "cannot write " + path.string());
  }
}

cv::Matx33d NominalCamera(const cv::Mat& frame) {
  const double focal = kFocalPerWidth * frame.cols;
  return {focal, 0, frame.cols / 2.0, 0, focal, frame.rows / 2.0, 0, 0, 1};
}

// transforms.json's camera-to-world matrix (OpenGL axes: x right, y up, z back) of a camera turned
// by `turn` (OpenCV axes) from the first frame's, whose OpenGL frame is the world.
nlohmann::json TransformMatrix(const cv::Matx33d& turn) {
  const cv::Matx33d flip = cv::Matx33d::diag(cv::Vec3d(1, -1, -1));
  const cv::Matx33d r = flip * turn * flip;
  return {{r(0, 0), r(0, 1), r(0, 2), 0},
          {r(1, 0), r(1, 1), r(1, 2), 0},
          {r(2, 0), r(2, 1), r(2, 2), 0},
          {0, 0, 0, 1}};
}

// The mono endoscope's turn per frame (prepare/camera_rotation.h), corners kept off the black
// outside the scope's view; what was estimated goes into recording.json.
std::vector<cv::Matx33d> EstimateTurns(const dicom::Recording& recording, nlohmann::json& record) {
  const cv::Mat& first = recording.left[0];
  static const int level = train::TrainConfig().outside_view_level;  // the training's default
  const std::vector<std::uint8_t> outside = scene::OutsideViewMask(recording.left, level);
  cv::Mat not_tissue;
  if (!outside.empty())
    not_tissue = cv::Mat(first.rows, first.cols, CV_8U, const_cast<std::uint8_t*>(outside.data())) * 255;
  const prepare::CameraTurns turns =
      prepare::EstimateCameraTurns(recording.left, NominalCamera(first), not_tissue);
  double widest = 0;
  for (const cv::Matx33d& r : turns.rotations)
    widest = std::max(widest, std::acos(std::clamp((cv::trace(r) - 1) / 2, -1.0, 1.0)));
  // Over the frames placed: an unplaced frame's 0 px counted as a perfect fit, so a run whose every
  // frame failed said "missed by 0.00 px" (found 2026-12-07).
  std::vector<double> misses;
  for (std::size_t i = 0; i < turns.residual_px.size(); ++i)
    if (turns.inliers[i] > 0) misses.push_back(turns.residual_px[i]);
  std::sort(misses.begin(), misses.end());
  const bool measured = !misses.empty();
  record["camera_turns"] = {
      {"widest_deg", widest * 180 / CV_PI},
      {"median_miss_px", measured ? nlohmann::json(misses[misses.size() / 2]) : nullptr},
      {"frames_unplaced", turns.unplaced},
      {"inliers", turns.inliers}};
  if (measured) {
    spdlog::info(
        "mono recording: the endoscope turns up to {:.1f} degrees from the first frame (tracks "
        "missed by {:.2f} px at the median of the {} frame(s) placed)",
        widest * 180 / CV_PI, misses[misses.size() / 2], misses.size());
  } else if (!turns.residual_px.empty()) {
    spdlog::warn("mono recording: no frame after the first could be placed: the endoscope is taken as fixed");
  }
  if (turns.unplaced > 0) {
    spdlog::warn(
        "mono recording: {} frame(s) could not be placed (too few tracks on tissue); each kept "
        "the turn of the frame before it",
        turns.unplaced);
  }
  return turns.rotations;
}

// `turns`: per frame, or empty for a fixed endoscope.
void WriteTransforms(const dicom::Recording& recording, const std::vector<cv::Matx33d>& turns,
                     const fs::path& clip_dir) {
  const int w = recording.left[0].cols, h = recording.left[0].rows;
  nlohmann::json frames = nlohmann::json::array();
  // The engine's times are in [0, 1]: the recording's span maps onto it.
  const double span = recording.times_s.back() > 0 ? recording.times_s.back() : 1.0;
  for (std::size_t i = 0; i < recording.left.size(); ++i) {
    frames.push_back({{"file_path", "images/" + eval::FrameFileName(static_cast<int>(i), ".png")},
                      {"transform_matrix", TransformMatrix(turns.empty() ? cv::Matx33d::eye() : turns[i])},
                      {"time", recording.times_s[i] / span}});
  }
  const nlohmann::json transforms = {{"fl_x", kFocalPerWidth * w},
                                     {"fl_y", kFocalPerWidth * w},
                                     {"cx", w / 2.0},
                                     {"cy", h / 2.0},
                                     {"w", w},
                                     {"h", h},
                                     {"near", kNear},
                                     {"far", kFar},
                                     {"frames", frames}};
  WriteFile(clip_dir / "transforms.json", transforms.dump(1), "clip cameras");
}

void WritePosesBounds(const dicom::Recording& recording, const fs::path& clip_dir) {
  const int w = recording.left[0].cols, h = recording.left[0].rows;
  const std::size_t n = recording.left.size();
  std::vector<double> rows(n * 17, 0.0);
  for (std::size_t i = 0; i < n; ++i) {
    double* row = &rows[i * 17];
    // LLFF's rotation columns are [down, right, back]: this is the identity once loaded (OpenGL).
    row[0 * 5 + 1] = 1;
    row[1 * 5 + 0] = -1;
    row[2 * 5 + 2] = 1;
    row[4] = h;
    row[9] = w;
    row[14] = kFocalPerWidth * w;
    row[15] = kNear;
    row[16] = kFar;
  }
  WriteNpyFloat64(clip_dir / "poses_bounds.npy", rows.data(), {n, 17});
}

// Every frame (each eye) scaled to `size` (area-averaged when smaller); refused when that would
// change the recording's aspect ratio (dicom::CheckSameShape, the server's check at submit too).
void ScaleFrames(dicom::Recording& recording, cv::Size size) {
  const cv::Size recorded = recording.left[0].size();
  dicom::CheckFrameFits({size.width, size.height}, {recorded.width, recorded.height}, "the recording");
  if (size.empty() || size == recorded) return;
  dicom::CheckSameShape({size.width, size.height}, {recorded.width, recorded.height});
  // Larger than recorded adds no detail and costs memory and time (it was taken silently; found
  // 2026-12-07).
  if (size.width > recorded.width) {
    spdlog::warn("--size {}x{} is larger than the recording's {}x{}: the frames are scaled up, which adds no "
                 "detail and costs memory and time",
                 size.width, size.height, recorded.width, recorded.height);
  }
  const int interpolation = size.width < recorded.width ? cv::INTER_AREA : cv::INTER_LINEAR;
  for (auto* eye : {&recording.left, &recording.right}) {
    for (cv::Mat& frame : *eye) cv::resize(frame, frame, size, 0, 0, interpolation);
  }
}

// The EndoNeRF layout a stereo clip takes spaces its frames evenly in time.
void WarnIfUneven(const std::vector<double>& times_s) {
  const std::size_t n = times_s.size();
  if (n <= 2) return;
  const double step = times_s.back() / static_cast<double>(n - 1);
  for (std::size_t i = 1; i < n; ++i) {
    if (std::abs(times_s[i] - times_s[i - 1] - step) > 0.25 * step) {
      spdlog::warn("stereo recording: frame times are uneven; the clip's times are evenly spaced");
      return;
    }
  }
}

// Stereo: both eyes go through the recording preparation (worker/prepare, issue 16) as a rectified
// pair with the nominal focal length and the loader's default baseline, which gives the clip a
// depth prior by stereo matching (in nominal units, as the recording has no calibration) and, for a
// moving endoscope, its poses (frames that cannot be placed are left out: returned, indices into
// the recording's frames). Poses that cannot be estimated at all leave the endoscope fixed, and a
// pair it cannot use (no matches to survey the disparities on) becomes a clip of both eyes without
// depth, as the log says; any other failure fails the job.
std::vector<int> WriteStereoClip(const dicom::Recording& recording, dicom::Endoscope endoscope,
                                 const fs::path& clip_dir) {
  WarnIfUneven(recording.times_s);
  const fs::path eyes = clip_dir.string() + ".eyes";
  fs::remove_all(eyes);
  WriteFrames(recording.left, eyes / "left");
  WriteFrames(recording.right, eyes / "right");
  prepare::PrepareOptions options;
  options.recording.left = eyes / "left";
  options.recording.right = eyes / "right";
  options.rectified = true;
  options.focal = kFocalPerWidth * recording.left[0].cols;
  options.baseline = scene::kDefaultStereoBaseline;
  options.estimate_poses = endoscope == dicom::Endoscope::kMoving;
  options.depth.eight_paths = options.estimate_poses;  // as `prepare --estimate-poses` chooses
  options.out = clip_dir;
  // The preparation, or why it could not (a recording it cannot use: InvalidArgument).
  std::string refusal;
  const auto prepared = [&]() -> std::optional<prepare::PrepareSummary> {
    fs::remove_all(clip_dir);
    try {
      return prepare::PrepareClip(options);
    } catch (const Error& e) {
      if (e.code() != ErrorCode::kInvalidArgument) throw;
      refusal = e.what();
      return std::nullopt;
    }
  };
  std::optional<prepare::PrepareSummary> summary = prepared();
  if (!summary && options.estimate_poses) {
    spdlog::warn("stereo recording: the endoscope's poses cannot be estimated ({}); it is taken as fixed",
                 refusal);
    options.estimate_poses = false;
    summary = prepared();
  }
  std::vector<int> dropped;
  if (summary) {
    spdlog::info("stereo recording: depth prior by stereo matching, {:.0f}% of the pixels; {}",
                 100 * summary->depth_coverage,
                 options.estimate_poses
                     ? fmt::format("the endoscope's poses estimated, reprojection RMS {:.2f} px",
                                   summary->pose_reprojection.rms)
                     : std::string("a fixed endoscope"));
    if (!summary->dropped.empty()) {
      spdlog::warn("stereo recording: {} frame(s) could not be placed and are left out of the clip",
                   summary->dropped.size());
    }
    dropped = summary->dropped;
  } else {
    spdlog::warn("stereo recording: no depth prior ({}); the clip has both eyes without depth", refusal);
    fs::create_directories(clip_dir);
    fs::rename(eyes / "left", clip_dir / "images");
    fs::rename(eyes / "right", clip_dir / "images_right");
    WritePosesBounds(recording, clip_dir);
  }
  fs::remove_all(eyes);
  return dropped;
}

}  // namespace

std::optional<RecordingClip> ClipFromRecording(const fs::path& input, const dicom::RecordingOptions& options,
                                               const fs::path& clip_dir) {
  if (!dicom::HoldsDicom(input)) return std::nullopt;
  dicom::Recording recording = dicom::ReadRecording(input, options);
  const cv::Size recorded = recording.left[0].size();
  ScaleFrames(recording, options.size);
  nlohmann::json camera_record = nlohmann::json::object();
  std::vector<int> dropped;  // kept frames (positions in `recording`) the clip leaves out
  if (recording.right.empty()) {
    fs::remove_all(clip_dir);
    fs::create_directories(clip_dir);
    WriteFrames(recording.left, clip_dir / "images");
    const auto turns = options.endoscope == dicom::Endoscope::kMoving
                           ? EstimateTurns(recording, camera_record)
                           : std::vector<cv::Matx33d>{};
    WriteTransforms(recording, turns, clip_dir);
  } else {
    dropped = WriteStereoClip(recording, options.endoscope, clip_dir);
    // Named by their numbers in the recording, as --frames counts (they were positions in the window).
    std::vector<int> numbers;
    for (const int position : dropped) numbers.push_back(recording.frame_numbers[position]);
    if (!numbers.empty()) camera_record["frames_dropped"] = numbers;
  }
  camera_record["endoscope"] = dicom::EndoscopeName(options.endoscope);
  RecordingClip clip;
  clip.clip_dir = clip_dir;
  clip.study = recording.study;
  for (std::size_t i = 0; i < recording.times_s.size(); ++i) {
    if (std::ranges::find(dropped, static_cast<int>(i)) == dropped.end())
      clip.times_s.push_back(recording.times_s[i]);
  }
  clip.summary = recording.description + "; " + std::to_string(clip.times_s.size()) + " of " +
                 std::to_string(recording.recording_frames) + " frame(s) kept, times from " +
                 recording.times_from +
                 (recording.right.empty() ? "" : ", stereo " + dicom::StereoLayoutName(options.stereo)) +
                 (recording.left[0].size() == recorded
                      ? ""
                      : fmt::format(", scaled to {}x{}", recording.left[0].cols, recording.left[0].rows));
  nlohmann::json record = {
      {"source", recording.description},
      {"stereo", dicom::StereoLayoutName(options.stereo)},
      {"frames",
       {{"start", options.frames.start}, {"end", options.frames.end}, {"step", options.frames.step}}},
      {"fps", options.fps},
      {"recording_frames", recording.recording_frames},
      {"recorded_size", {recorded.width, recorded.height}},
      {"size", {recording.left[0].cols, recording.left[0].rows}},
      {"times_from", recording.times_from},
      {"times_s", clip.times_s},
      {"focal_per_width", kFocalPerWidth},
      {"near", kNear},
      {"far", kFar}};
  record.update(camera_record);
  WriteFile(clip_dir / "recording.json", record.dump(1), "recording description");
  spdlog::info("DICOM recording: {}", clip.summary);
  return clip;
}

}  // namespace endorecon::worker
