#include "worker/prepare/prepare_clip.h"

#include <signal.h>
#include <spdlog/spdlog.h>
#include <tbb/parallel_for.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cmath>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <thread>

#include "common/error.h"
#include "common/npy.h"
#include "common/output_folder.h"
#include "worker/prepare/clip_writer.h"
#include "worker/prepare/eye_sync.h"
#include "worker/prepare/pose_estimator.h"
#include "worker/prepare/pose_file.h"
#include "worker/prepare/preview_image.h"
#include "worker/prepare/stereo_rectifier.h"

namespace endorecon::prepare {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

constexpr int kSurveyFrames = 6;
// Below it, a warning.
constexpr double kLowDepthCoverage = 0.4;
const cv::Matx44d kFlipYz(1, 0, 0, 0, 0, -1, 0, 0, 0, 0, -1, 0, 0, 0, 0, 1);  // OpenCV <-> OpenGL axes

std::string SizeText(cv::Size size) { return std::to_string(size.width) + "x" + std::to_string(size.height); }

void ValidateOptions(const PrepareOptions& o) {
  if (o.out.empty()) FailInvalid("no output folder (-o)");
  if (o.rectified == !o.calibration.empty()) {
    FailInvalid(
        "give either --calibration FILE (or two ROS camera_info files) or --rectified --focal PX --baseline "
        "B");
  }
  if (!o.poses.empty() && o.estimate_poses) FailInvalid("give --poses FILE or --estimate-poses, not both");
}

// The output folder: `out` must be absent, empty or an earlier prepared clip. Frames go to a
// temporary sibling, renamed over `out` by Commit(); until then the destructor removes it.
class StagedFolder {
 public:
  explicit StagedFolder(const fs::path& out) : out_(fs::absolute(out).lexically_normal()) {
    // Before the recording is read; the staging folder goes beside `out` (found 2026-12-07: a
    // read-only folder was "UNAVAILABLE: .../.clip.preparing-PID: cannot create").
    RequireWritableFolder(out_.parent_path(), "-o " + out_.string() + ": its parent folder");
    if (fs::exists(out_) &&
        (!fs::is_directory(out_) || (!fs::is_empty(out_) && !fs::exists(out_ / "prepare.json")))) {
      FailInvalid(out_.string() + ": exists and is not empty (and holds no prepared clip to replace)");
    }
    const std::string prefix = "." + out_.filename().string() + ".preparing-";
    staging_ = out_.parent_path() / (prefix + std::to_string(::getpid()));
    RemoveAbandoned(prefix);
    std::error_code error;
    fs::remove_all(staging_, error);
    fs::create_directories(staging_, error);
    if (error)
      Fail(ErrorCode::kUnavailable,
           staging_.string() + ": cannot create the staging folder (" + error.message() + ")");
  }
  ~StagedFolder() {
    std::error_code ignored;
    if (!committed_) fs::remove_all(staging_, ignored);
  }
  StagedFolder(const StagedFolder&) = delete;
  StagedFolder& operator=(const StagedFolder&) = delete;

  const fs::path& path() const { return staging_; }

  // A staging folder of the same output whose process is gone (killed before its destructor ran):
  // removed, so killed runs leave no frames behind for good.
  void RemoveAbandoned(const std::string& prefix) const {
    std::error_code error;
    for (const auto& entry : fs::directory_iterator(out_.parent_path(), error)) {
      const std::string name = entry.path().filename().string();
      if (!name.starts_with(prefix)) continue;
      const std::string pid = name.substr(prefix.size());
      if (pid.empty() || pid.find_first_not_of("0123456789") != std::string::npos || pid.size() > 9) continue;
      if (::kill(static_cast<pid_t>(std::stol(pid)), 0) != 0 && errno == ESRCH) {
        std::error_code ignored;
        fs::remove_all(entry.path(), ignored);
        spdlog::info("removed {}: the staging folder of a run that ended before finishing",
                     entry.path().string());
      }
    }
  }

  void Commit() {
    std::error_code error;
    const fs::path old =
        out_.parent_path() / ("." + out_.filename().string() + ".replaced-" + std::to_string(::getpid()));
    if (fs::exists(out_)) fs::rename(out_, old, error);
    if (!error) fs::rename(staging_, out_, error);
    if (error)
      Fail(ErrorCode::kUnavailable,
           out_.string() + ": cannot move the prepared clip in place (" + error.message() + ")");
    committed_ = true;
    fs::remove_all(old, error);
  }

 private:
  fs::path out_, staging_;
  bool committed_ = false;
};

// Raw 0/255 masks of each eye from the excluded rectangles, given in the recording's stored frames
// (for a side-by-side or top-bottom recording the whole frame, so a region lands in the eye it
// covers; for two sources each eye's own frame, a region applying to both).
std::array<cv::Mat, 2> ExcludedRaw(const std::vector<PixelRect>& rects, StereoLayout layout, cv::Size eye) {
  const cv::Size stored = layout == StereoLayout::kSideBySide  ? cv::Size(2 * eye.width, eye.height)
                          : layout == StereoLayout::kTopBottom ? cv::Size(eye.width, 2 * eye.height)
                                                               : eye;
  cv::Mat whole(stored, CV_8U, cv::Scalar(0));
  for (const PixelRect& r : rects) {
    if (r.x + r.width > stored.width || r.y + r.height > stored.height) {
      FailInvalid("--exclude " + std::to_string(r.x) + "," + std::to_string(r.y) + "," +
                  std::to_string(r.width) + "," + std::to_string(r.height) +
                  " reaches outside the recording's " + SizeText(stored) + " frames");
    }
    whole(cv::Rect(r.x, r.y, r.width, r.height)).setTo(255);
  }
  if (layout == StereoLayout::kTwoSources) return {whole, whole.clone()};
  const cv::Rect second = layout == StereoLayout::kSideBySide
                              ? cv::Rect(eye.width, 0, eye.width, eye.height)
                              : cv::Rect(0, eye.height, eye.width, eye.height);
  return {whole(cv::Rect(0, 0, eye.width, eye.height)).clone(), whole(second).clone()};
}

// The tool masks (a video or folder of the raw left eye), read in step with the recording.
class MaskReader {
 public:
  // `skip`: the left eye's first frames skipped (--skip-left): their masks are skipped too.
  MaskReader(const fs::path& path, bool tool_black, cv::Size eye, int skip)
      : tool_black_(tool_black), skip_(skip) {
    if (path.empty()) return;
    source_ = OpenFrameSource(path);
    if (source_->frame_size() != eye) {
      FailInvalid(source_->name() + " frame 0: masks of " + SizeText(source_->frame_size()) +
                  " do not match the left eye's " + SizeText(eye) + " frames");
    }
    if (const int skipped = SkipFrames(*source_, skip); skipped < skip) {
      FailInvalid(source_->name() + ": the masks end after " + std::to_string(skipped) +
                  " frames, before the " + std::to_string(skip) + " of --skip-left");
    }
  }
  bool active() const { return source_ != nullptr; }

  // Before any frame is prepared, where both counts are known (folders): the masks' against the left
  // eye's file, `left_file_frames` (-1: not known). A wrong count was found only after the whole
  // recording was prepared (found 2026-12-07).
  void CheckCount(int left_file_frames) const {
    if (!source_ || left_file_frames < 0 || !source_->count_is_exact()) return;
    const int masks = source_->announced_frames();
    if (masks > left_file_frames) TooMany(left_file_frames);
    if (masks < left_file_frames) {
      FailInvalid(source_->name() + ": holds " + std::to_string(masks) +
                  " mask frames, fewer than the left eye's " + std::to_string(left_file_frames) +
                  AfterSkip(left_file_frames - skip_) + " (one mask per frame)");
    }
  }

  // The tool mask (0/255) of recording frame `index`, or empty without masks.
  cv::Mat Next(int index) {
    if (!source_) return {};
    SourceFrame frame;
    if (!source_->Next(frame)) Short(index);
    cv::Mat grey, tool;
    cv::cvtColor(frame.image, grey, cv::COLOR_BGR2GRAY);
    // Threshold at half: video compression blurs a mask's two values.
    cv::threshold(grey, tool, 127, 255, tool_black_ ? cv::THRESH_BINARY_INV : cv::THRESH_BINARY);
    return tool;
  }
  void Skip(int index) {
    if (source_ && !source_->Skip()) Short(index);
  }
  // After the `pairs` read: the masks must end with the left eye's `left_frames` (both after the skip).
  void CheckEnd(int pairs, int left_frames) {
    if (!source_) return;
    for (int index = pairs; index < left_frames; ++index) Skip(index);
    if (source_->Skip()) TooMany(left_frames + skip_);
  }

 private:
  // Counts are said as the files count them, and after the skip beside (found 2026-12-07).
  std::string AfterSkip(int frames) const {
    return skip_ > 0
               ? " (" + std::to_string(frames) + " after the " + std::to_string(skip_) + " of --skip-left)"
               : "";
  }
  // `left_file_frames`: the left eye's file's, its skip included.
  [[noreturn]] void TooMany(int left_file_frames) const {
    FailInvalid(source_->name() + ": holds more mask frames than the left eye's " +
                std::to_string(left_file_frames) + AfterSkip(left_file_frames - skip_) +
                " (one mask per frame)");
  }
  [[noreturn]] void Short(int index) const {
    FailInvalid(source_->name() + " frame " + std::to_string(index + skip_) + ": the masks end after " +
                std::to_string(index + skip_) + " frames" + AfterSkip(index) +
                " while the recording goes on (one mask per frame)");
  }
  std::unique_ptr<FrameSource> source_;
  bool tool_black_;
  int skip_;
};

// How frames are placed: fixed (identity), from a pose file, or estimated.
class Placer {
 public:
  Placer(const PrepareOptions& options, const RectifiedCamera& camera) {
    // The clip's camera is the rectified left eye: raw pose times the rectifying rotation's inverse.
    rectify_ = cv::Matx44d::eye();
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) rectify_(r, c) = camera.left_rotation(c, r);
    }
    if (!options.poses.empty()) {
      file_ = options.poses.string();
      skip_ = options.recording.skip_left;
      poses_ = ReadPoseFile(options.poses);
      for (std::size_t i = 1; i < poses_.size(); ++i)
        moving_ = moving_ || cv::norm(poses_[i] - poses_[0], cv::NORM_INF) > 1e-9;
    }
    if (options.estimate_poses) estimator_.emplace(camera.Matrix(), camera.size);
  }

  bool moving() const { return moving_ || estimator_.has_value(); }
  std::string source() const { return estimator_ ? "estimated" : poses_.empty() ? "fixed" : "file " + file_; }

  std::optional<cv::Matx44d> Place(int index, const PreparedFrame& frame) {
    // Without a pose file the clip's world is the first camera's frame in OpenGL axes (its pose
    // in the layout files is the identity); the estimator's is that frame in OpenCV axes.
    if (estimator_) {
      const auto pose = estimator_->Add(frame.left, frame.depth, frame.excluded);
      if (!pose) return std::nullopt;
      return kFlipYz * *pose;
    }
    if (poses_.empty()) return kFlipYz;
    // One pose per frame of the left eye's file: those of the frames --skip-left drops are skipped
    // too, as its masks are (found 2026-12-07).
    if (index + skip_ >= static_cast<int>(poses_.size())) {
      FailInvalid(file_ + ": holds " + std::to_string(poses_.size()) +
                  " poses but the recording has more frames (frame " + std::to_string(index + skip_) +
                  " has none" + AfterSkip(index) + ")");
    }
    return poses_[static_cast<std::size_t>(index + skip_)] * rectify_;
  }
  // `left_frames`: the left eye's after its skip (StereoSource::left_eye_frames; -1: not known, the
  // right eye's recording ended first).
  void CheckCount(int left_frames) const {
    if (!poses_.empty() && left_frames >= 0 && static_cast<int>(poses_.size()) != left_frames + skip_) {
      FailInvalid(file_ + ": holds " + std::to_string(poses_.size()) + " poses but the recording has " +
                  std::to_string(left_frames + skip_) + " frames" +
                  (skip_ > 0 ? " (" + std::to_string(skip_) + " of them dropped by --skip-left)" : "") +
                  " (one pose per frame)");
    }
  }
  json Report() const {
    json report = {{"source", source()}};
    if (estimator_) {
      const ErrorStats e = estimator_->reprojection_error();
      report["reprojection_error_px"] = {
          {"median", e.median}, {"rms", e.rms}, {"p95", e.p95}, {"count", e.count}};
    }
    return report;
  }
  ErrorStats reprojection() const { return estimator_ ? estimator_->reprojection_error() : ErrorStats{}; }

 private:
  std::string AfterSkip(int index) const {
    return skip_ > 0 ? ", the pair " + std::to_string(index) + " after --skip-left " + std::to_string(skip_)
                     : "";
  }
  std::string file_;
  int skip_ = 0;
  std::vector<cv::Matx44d> poses_;
  bool moving_ = false;
  cv::Matx44d rectify_;
  std::optional<PoseEstimator> estimator_;
};

// The frames the survey looks at: up to kSurveyFrames spread evenly over the selection.
std::vector<int> SurveyFrames(const FrameRange& range, int announced) {
  std::vector<int> selected;
  const int end = announced > 0 ? (range.end < 0 ? announced : std::min(range.end, announced)) : -1;
  if (end < 0) {
    for (int i = 0; i < kSurveyFrames; ++i) selected.push_back(range.start + i * range.step);
    return selected;
  }
  const int count = end > range.start ? (end - range.start + range.step - 1) / range.step : 0;
  for (int i = 0; i < std::min(count, kSurveyFrames); ++i) {
    const int k = count <= kSurveyFrames ? i : i * (count - 1) / (kSurveyFrames - 1);
    selected.push_back(range.start + k * range.step);
  }
  return selected;
}

StereoSurvey Survey(const PrepareOptions& options, const StereoRectifier& rectifier,
                    const cv::Mat& excluded_left, int announced) {
  StereoSurvey survey;
  StereoSource source(options.recording);
  StereoFrame frame;
  const cv::Mat allowed = 255 - excluded_left;
  int position = 0;
  for (int wanted : SurveyFrames(options.frames, announced)) {
    for (; position < wanted; ++position) {
      if (!source.Skip()) return survey;
    }
    if (!source.Next(frame)) return survey;
    ++position;
    SurveyRawPair(frame.left, frame.right, survey);
    SurveyPair(rectifier.Left(frame.left), rectifier.Right(frame.right), allowed, survey);
  }
  return survey;
}

// One selected frame on its way through the batch.
struct Item {
  StereoFrame raw;
  cv::Mat tool;  // raw left eye, 0/255, or empty
  PreparedFrame prepared;
  double coverage = 0;        // share of non-excluded pixels with a depth
  cv::Vec2f disparity{0, 0};  // 1st and 99th percentile of the frame's disparities
};

cv::Vec2f DisparityPercentiles(const cv::Mat& disparity) {
  std::vector<float> values;
  for (int y = 0; y < disparity.rows; y += 2) {
    const float* d = disparity.ptr<float>(y);
    for (int x = 0; x < disparity.cols; x += 2) {
      if (d[x] > 0) values.push_back(d[x]);
    }
  }
  if (values.empty()) return {0, 0};
  std::sort(values.begin(), values.end());
  return {values[values.size() / 100], values[values.size() * 99 / 100]};
}

json StatsJson(const ErrorStats& e) {
  return {{"median", e.median}, {"rms", e.rms}, {"p95", e.p95}, {"count", e.count}};
}

json MatrixJson(const cv::Matx33d& m) {
  json rows = json::array();
  for (int r = 0; r < 3; ++r) rows.push_back({m(r, 0), m(r, 1), m(r, 2)});
  return rows;
}

std::string LayoutName(StereoLayout layout) {
  return layout == StereoLayout::kSideBySide  ? "side-by-side"
         : layout == StereoLayout::kTopBottom ? "top-bottom"
                                              : "two sources";
}

class Preparation {
 public:
  Preparation(const PrepareOptions& options, const PrepareHooks& hooks)
      : options_(options),
        hooks_(hooks),
        staged_(options.out),
        source_(options.recording, StereoSource::UnequalLengths::kRead) {
    const cv::Size eye = source_.eye_size();
    calibration_ = options.rectified ? RectifiedCalibration(eye, options.focal, options.baseline)
                                     : LoadStereoCalibration(options.calibration);
    CheckCalibrationFits(calibration_, eye);
    if (calibration_.image_size == cv::Size()) calibration_.image_size = eye;  // a file that names none
    rectifier_ =
        std::make_unique<StereoRectifier>(calibration_, cv::Size(options.size.width, options.size.height));
    camera_ = rectifier_->camera();
    const auto raw = ExcludedRaw(options.exclude, options.recording.layout, eye);
    excluded_[0] = rectifier_->LeftMask(raw[0]);
    excluded_[1] = rectifier_->RightMask(raw[1]);
    masks_ = std::make_unique<MaskReader>(options.masks, options.masks_tool_black, eye,
                                          options.recording.skip_left);
    placer_ = std::make_unique<Placer>(options, camera_);
    // The eyes' timing before their lengths: two folders cut apart differ in length, and the frames
    // to skip are what to say (found 2026-12-07).
    CheckEyesInStep(options.recording);
    source_.RequireEqualLengths();
    // The masks' and poses' counts, where the files say them, before any frame is prepared.
    if (const int left = source_.left_file_frames(); left >= 0) {
      masks_->CheckCount(left);
      placer_->CheckCount(left - options.recording.skip_left);
    }
    survey_ = Survey(options, *rectifier_, excluded_[0], source_.announced_frames());
    survey_.CheckTwoViews(source_.name());
    survey_.CheckEyeOrder(source_.name());
    if (survey_.disparities.size() < StereoSurvey::kEyeOrderMatches) {
      spdlog::warn(
          "{}: only {} point(s) of the left eye were found in the right eye on the same row: is it "
          "a stereo recording, of this layout, with this rig's calibration? (depth will be sparse)",
          source_.name(), survey_.disparities.size());
    }
    range_ = survey_.Range(camera_.size.width);
    depth_ = std::make_unique<StereoDepth>(options.depth, range_, camera_.focal, camera_.baseline);
    layout_ = placer_->moving() ? ClipLayout::kTransforms : ClipLayout::kEndoNerf;
    writer_ = std::make_unique<ClipWriter>(staged_.path(), layout_, camera_, HasMasks());
    spdlog::info("preparing {} ({} eyes) -> {}x{} clip, f = {:.2f} px, baseline {:.4g}, disparities [{}, {})",
                 source_.name(), SizeText(eye), camera_.size.width, camera_.size.height, camera_.focal,
                 camera_.baseline, range_.min, range_.max());
  }

  PrepareSummary Run() {
    const auto start = std::chrono::steady_clock::now();
    const int total = SelectedCount();
    const std::size_t batch_size = 2 * std::max(1u, std::thread::hardware_concurrency());
    int index = 0;
    while (true) {
      if (hooks_.should_stop && hooks_.should_stop())
        Fail(ErrorCode::kCancelled, "preparation stopped on request");
      std::vector<Item> batch;
      bool more = true;
      while (more && batch.size() < batch_size) more = ReadSelected(index, batch);
      Process(batch);
      Place(batch);
      if (hooks_.on_frame) hooks_.on_frame(static_cast<int>(placements_.size() + dropped_.size()), total);
      if (!more) break;
    }
    recording_frames_ = index;
    // The masks end with the left eye's recording: past the pairs by a video's trailing frames, and
    // not known where eyes cut apart ended with the right eye (its masks go on past the pairs).
    if (const int left = source_.left_eye_frames(); left >= 0) masks_->CheckEnd(recording_frames_, left);
    placer_->CheckCount(source_.left_eye_frames());
    if (placements_.empty()) {
      FailInvalid(
          source_.name() + ": no frame " +
          (dropped_.empty() ? "selected by --frames " + options_.frames.ToString() : "could be placed") +
          " (the recording has " + std::to_string(recording_frames_) + ")");
    }
    const double near = camera_.focal * camera_.baseline / range_.max();
    const double far = camera_.focal * camera_.baseline / range_.floor;
    writer_->Finish(placements_, near, far);
    WritePreview(near, far);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    PrepareSummary summary = Summary(seconds);
    if (summary.depth_coverage < kLowDepthCoverage) {
      // Stereo tissue is mostly matched (80-90% on the synthetic rig); this little is a recording,
      // layout, calibration or mask of another kind (found 2026-12-06: each prepared silently).
      spdlog::warn(
          "{}: depth for {:.0f}% of the frames' pixels only (outside masks and --exclude): is it a "
          "stereo recording of this layout and rig, and do the masks mark the tools, not the tissue "
          "(--mask-tool)? Training leans on the images alone where depth is missing",
          source_.name(), 100 * summary.depth_coverage);
    }
    WriteReport(summary, near, far);
    staged_.Commit();
    return summary;
  }

 private:
  bool HasMasks() const { return masks_->active() || !options_.exclude.empty(); }

  int SelectedCount() const {
    const int announced = source_.announced_frames();
    if (announced < 0) return -1;
    const int end = options_.frames.end < 0 ? announced : std::min(options_.frames.end, announced);
    return end > options_.frames.start
               ? (end - options_.frames.start + options_.frames.step - 1) / options_.frames.step
               : 0;
  }

  // Reads recording frames up to and including the next selected one; false at the recording's end.
  bool ReadSelected(int& index, std::vector<Item>& batch) {
    while (true) {
      if (!options_.frames.Selects(index)) {
        if (!source_.Skip()) return false;
        masks_->Skip(index++);
        continue;
      }
      Item item;
      if (!source_.Next(item.raw)) return false;
      item.tool = masks_->Next(index++);
      batch.push_back(std::move(item));
      return true;
    }
  }

  void Process(std::vector<Item>& batch) const {
    // Tool masks grow by a pixel or two: rectification blends a tool's edge into its neighbours.
    const int grow = std::max(1, camera_.size.width / 320);
    const cv::Mat kernel = cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(2 * grow + 1, 2 * grow + 1));
    tbb::parallel_for(std::size_t{0}, batch.size(), [&](std::size_t i) {
      Item& item = batch[i];
      PreparedFrame& out = item.prepared;
      out.left = rectifier_->Left(item.raw.left);
      out.right = rectifier_->Right(item.raw.right);
      const StereoDepthResult result = depth_->Compute(out.left, out.right, excluded_[0], excluded_[1]);
      out.depth = result.depth;
      if (HasMasks()) {
        out.excluded = excluded_[0].clone();
        if (!item.tool.empty()) {
          cv::Mat tool;
          cv::dilate(rectifier_->LeftMask(item.tool), tool, kernel);
          out.excluded |= tool;
        }
      }
      const cv::Mat kept =
          out.excluded.empty() ? cv::Mat(out.depth.size(), CV_8U, cv::Scalar(255)) : 255 - out.excluded;
      const int kept_pixels = cv::countNonZero(kept);
      item.coverage =
          kept_pixels > 0 ? static_cast<double>(cv::countNonZero((out.depth > 0) & kept)) / kept_pixels : 0;
      item.disparity = DisparityPercentiles(result.disparity);
      item.raw.left.release();
      item.raw.right.release();
    });
  }

  void Place(std::vector<Item>& batch) {
    std::vector<std::pair<int, const Item*>> to_write;
    for (const Item& item : batch) {
      const std::optional<cv::Matx44d> pose = placer_->Place(item.raw.index, item.prepared);
      if (!pose) {
        dropped_.push_back(item.raw.index);
        continue;
      }
      to_write.emplace_back(static_cast<int>(placements_.size()), &item);
      placements_.push_back({*pose, item.raw.time_s});
      frames_report_.push_back({{"clip_frame", to_write.back().first},
                                {"recording_frame", item.raw.index},
                                {"time_s", item.raw.time_s},
                                {"depth_coverage", item.coverage},
                                {"disparity_p1_p99", {item.disparity[0], item.disparity[1]}}});
      coverage_sum_ += item.coverage;
    }
    tbb::parallel_for(std::size_t{0}, to_write.size(), [&](std::size_t i) {
      writer_->Write(to_write[i].first, to_write[i].second->prepared);
    });
  }

  void WritePreview(double near, double far) const {
    const std::string name = ClipFrameName(static_cast<int>(placements_.size() / 2));
    const fs::path dir = staged_.path();
    const cv::Mat frame = cv::imread((dir / "images" / (name + ".png")).string());
    NpyArray array = ReadNpy(dir / "depth" / (name + ".npy"));
    cv::Mat depth;
    cv::Mat(frame.rows, frame.cols, CV_64F, array.data.data()).convertTo(depth, CV_32F);
    cv::Mat excluded;
    if (HasMasks()) {
      excluded = cv::imread((dir / "masks" / (name + ".png")).string(), cv::IMREAD_GRAYSCALE);
      if (layout_ == ClipLayout::kTransforms) excluded = 255 - excluded;
    }
    if (!cv::imwrite((dir / "preview.png").string(), PreviewImage(frame, depth, excluded, near, far))) {
      Fail(ErrorCode::kUnavailable, "cannot write " + (dir / "preview.png").string());
    }
  }

  PrepareSummary Summary(double seconds) const {
    PrepareSummary s;
    s.clip = fs::absolute(options_.out).lexically_normal();
    s.layout = layout_ == ClipLayout::kEndoNerf ? "endonerf" : "transforms";
    s.frames = static_cast<int>(placements_.size());
    s.dropped = dropped_;
    s.recording_frames = recording_frames_;
    s.seconds = seconds;
    s.epipolar_error = survey_.epipolar_error();
    s.pose_reprojection = placer_->reprojection();
    s.depth_coverage = coverage_sum_ / std::max<std::size_t>(1, placements_.size());
    return s;
  }

  void WriteReport(const PrepareSummary& s, double near, double far) const {
    json calibration = {{"kind", calibration_.kind},
                        {"source", calibration_.source},
                        {"image_size", {calibration_.image_size.width, calibration_.image_size.height}},
                        {"baseline", calibration_.baseline()}};
    json exclude = json::array();
    for (const PixelRect& r : options_.exclude) exclude.push_back({r.x, r.y, r.width, r.height});
    json report = {{"recording",
                    {{"source", source_.name()},
                     {"layout", LayoutName(options_.recording.layout)},
                     {"eye_size", {source_.eye_size().width, source_.eye_size().height}},
                     {"frames", recording_frames_}}},
                   {"options",
                    {{"frames", options_.frames.ToString()},
                     {"skip_left", options_.recording.skip_left},
                     {"skip_right", options_.recording.skip_right},
                     {"size", {options_.size.width, options_.size.height}},
                     {"masks", options_.masks.string()},
                     {"masks_tool", options_.masks_tool_black ? "black" : "white"},
                     {"exclude", exclude},
                     {"poses", options_.poses.string()},
                     {"estimate_poses", options_.estimate_poses},
                     {"depth", options_.depth.Describe()}}},
                   {"calibration", calibration},
                   {"rectification",
                    {{"size", {camera_.size.width, camera_.size.height}},
                     {"focal_px", camera_.focal},
                     {"principal_point_px", {camera_.size.width / 2.0, camera_.size.height / 2.0}},
                     {"baseline", camera_.baseline},
                     {"scale", camera_.scale},
                     {"passthrough", rectifier_->passthrough()},
                     {"left_rotation", MatrixJson(camera_.left_rotation)},
                     {"right_rotation", MatrixJson(camera_.right_rotation)},
                     {"epipolar_error_px", StatsJson(s.epipolar_error)}}},
                   {"depth",
                    {{"method", options_.depth.Describe()},
                     {"unit", "the calibration's (of T)"},
                     {"disparity_range_px", {range_.min, range_.max()}},
                     {"disparity_floor_px", range_.floor},
                     {"surveyed_matches", survey_.disparities.size()},
                     {"near", near},
                     {"far", far},
                     {"mean_coverage", s.depth_coverage}}},
                   {"poses", placer_->Report()},
                   {"layout", s.layout},
                   {"frames_in_clip", s.frames},
                   {"dropped_frames", dropped_},
                   {"frames", frames_report_},
                   {"seconds", s.seconds},
                   {"frames_per_second",
                    (s.frames + static_cast<double>(s.dropped.size())) / std::max(1e-9, s.seconds)}};
    std::ofstream file(staged_.path() / "prepare.json");
    file << report.dump(1) << "\n";
    file.close();
    if (!file) Fail(ErrorCode::kUnavailable, "cannot write " + (staged_.path() / "prepare.json").string());
  }

  const PrepareOptions& options_;
  const PrepareHooks& hooks_;
  StagedFolder staged_;
  StereoSource source_;
  StereoCalibration calibration_;
  std::unique_ptr<StereoRectifier> rectifier_;
  RectifiedCamera camera_;
  cv::Mat excluded_[2];
  std::unique_ptr<MaskReader> masks_;
  std::unique_ptr<Placer> placer_;
  StereoSurvey survey_;
  DisparityRange range_;
  std::unique_ptr<StereoDepth> depth_;
  ClipLayout layout_ = ClipLayout::kEndoNerf;
  std::unique_ptr<ClipWriter> writer_;
  std::vector<FramePlacement> placements_;
  std::vector<int> dropped_;
  json frames_report_ = json::array();
  double coverage_sum_ = 0;
  int recording_frames_ = 0;
};

}  // namespace

PrepareSummary PrepareClip(const PrepareOptions& options, const PrepareHooks& hooks) {
  ValidateOptions(options);
  Preparation preparation(options, hooks);
  return preparation.Run();
}

}  // namespace endorecon::prepare
