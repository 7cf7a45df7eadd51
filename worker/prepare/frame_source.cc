#include "worker/prepare/frame_source.h"

#include <spdlog/spdlog.h>

#include <cmath>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>
#include <vector>

#include "common/clip_files.h"
#include "common/error.h"
#include "common/file_read.h"
#include "worker/engine/scene/image_file.h"
#include "worker/prepare/video_header.h"

namespace endorecon::prepare {
namespace {

namespace fs = std::filesystem;

std::string SizeText(cv::Size size) { return std::to_string(size.width) + "x" + std::to_string(size.height); }

// Any 8- or 16-bit grey, BGR or BGRA image as 8-bit BGR.
void CheckFrameSize(const std::string& where, cv::Size found, cv::Size expected) {
  if (found != expected) {
    FailInvalid(where + ": size " + SizeText(found) + " differs from the recording's " + SizeText(expected) +
                " (all frames must share one size)");
  }
}

class ImageFolderSource final : public FrameSource {
 public:
  explicit ImageFolderSource(const fs::path& dir)
      : name_(dir.string()), files_(ListFiles(dir, ImageExtensions())) {
    if (files_.empty()) FailInvalid(name_ + ": the folder holds no image (png, jpg, jpeg, bmp, tif, tiff)");
    size_ = Decode(0).size();
  }

  const std::string& name() const override { return name_; }
  cv::Size frame_size() const override { return size_; }
  int announced_frames() const override { return static_cast<int>(files_.size()); }
  bool count_is_exact() const override { return true; }

  bool Next(SourceFrame& frame) override {
    if (next_ >= files_.size()) return false;
    frame.image = Decode(next_);
    CheckFrameSize(files_[next_].string(), frame.image.size(), size_);
    frame.index = static_cast<int>(next_);
    frame.time_s = static_cast<double>(next_) * kImageFolderFramePeriod;
    ++next_;
    return true;
  }
  bool Skip() override {
    if (next_ >= files_.size()) return false;
    ++next_;
    return true;
  }

 private:
  cv::Mat Decode(std::size_t i) const {
    try {
      return scene::DecodeImageFileAsBgr8(files_[i]);
    } catch (const Error& e) {
      FailInvalid(std::string(e.what()) + " (frame " + std::to_string(i) + ")");
    }
  }

  std::string name_;
  std::vector<fs::path> files_;
  std::size_t next_ = 0;
  cv::Size size_;
};

class VideoFileSource final : public FrameSource {
 public:
  explicit VideoFileSource(const fs::path& file) : name_(file.string()) {
    if (!capture_.open(name_, cv::CAP_FFMPEG) || !capture_.grab()) {
      FailInvalid(name_ +
                  ": cannot open it as a video (unreadable, truncated, or not a video FFmpeg decodes)");
    }
    cv::Mat first;
    if (!capture_.retrieve(first) || first.empty()) FailInvalid(name_ + " frame 0: cannot decode the frame");
    size_ = first.size();
    const double count = capture_.get(cv::CAP_PROP_FRAME_COUNT);
    announced_ = count >= 1 && std::isfinite(count) ? static_cast<int>(std::lround(count)) : -1;
    if (const VideoHeader header = ReadVideoHeader(file); header.frames > 0) announced_ = header.frames;
    fps_ = capture_.get(cv::CAP_PROP_FPS);
    pending_ = scene::ToBgr8(first);
  }

  const std::string& name() const override { return name_; }
  cv::Size frame_size() const override { return size_; }
  int announced_frames() const override { return announced_; }
  double frame_rate() const override { return fps_ > 0 && std::isfinite(fps_) ? fps_ : 0; }

  bool Next(SourceFrame& frame) override { return Advance(&frame); }
  bool Skip() override { return Advance(nullptr); }

 private:
  // The first frame was decoded when opening (to learn the size); later ones are grabbed here and
  // decoded only when wanted.
  bool Advance(SourceFrame* frame) {
    const int index = decoded_;
    if (!pending_.empty()) {
      if (frame) frame->image = std::move(pending_);
      pending_.release();
    } else if (!capture_.grab()) {
      CheckComplete(index);
      return false;
    } else if (frame) {
      cv::Mat image;
      if (!capture_.retrieve(image) || image.empty()) {
        FailInvalid(name_ + " frame " + std::to_string(index) +
                    ": cannot decode the frame (a damaged video?)");
      }
      frame->image = scene::ToBgr8(image);
      CheckFrameSize(name_ + " frame " + std::to_string(index), frame->image.size(), size_);
    }
    ++decoded_;
    if (frame) {
      frame->index = index;
      // FFmpeg's timestamp of the grabbed frame where the container has one, else the nominal rate.
      const double time_ms = index > 0 ? capture_.get(cv::CAP_PROP_POS_MSEC) : 0.0;
      frame->time_s = index == 0 || time_ms > 0 ? time_ms / 1000.0
                                                : index / (fps_ > 0 && std::isfinite(fps_) ? fps_ : 25.0);
    }
    return true;
  }

  // A video that stops well short of the frames its header announces was cut off. Containers
  // whose count is an estimate (from duration and rate) may be off by a frame or two.
  void CheckComplete(int decoded) const {
    if (announced_ > 0 && decoded < announced_ - 2) {
      FailInvalid(name_ + " frame " + std::to_string(decoded) + ": the video ends after " +
                  std::to_string(decoded) + " of the " + std::to_string(announced_) +
                  " frames its header announces (truncated or damaged)");
    }
    if (announced_ > 0 && decoded != announced_) {
      spdlog::warn("{}: decoded {} frames where the header announces {}", name_, decoded, announced_);
    }
  }

  std::string name_;
  cv::VideoCapture capture_;
  cv::Size size_;
  int announced_ = -1;
  double fps_ = 0;
  int decoded_ = 0;
  cv::Mat pending_;
};

}  // namespace

int SkipFrames(FrameSource& source, int count) {
  int skipped = 0;
  while (skipped < count && source.Skip()) ++skipped;
  return skipped;
}

std::unique_ptr<FrameSource> OpenFrameSource(const fs::path& path) {
  if (!fs::exists(path)) Fail(ErrorCode::kNotFound, path.string() + ": does not exist");
  if (fs::is_directory(path)) return std::make_unique<ImageFolderSource>(path);
  RequireRegularFile(path, "video file or folder of frames");  // FFmpeg would wait on a FIFO for ever
  return std::make_unique<VideoFileSource>(path);
}

}  // namespace endorecon::prepare
