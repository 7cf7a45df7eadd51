#include "worker/engine/eval/video_writer.h"

#include <cmath>
#include <opencv2/core.hpp>
#include <opencv2/videoio.hpp>

#include "common/error.h"
#include "worker/engine/eval/image_size.h"
#include "worker/engine/eval/quantize.h"

namespace endorecon::eval {

struct VideoWriter::State {
  cv::VideoWriter writer;
  std::filesystem::path path;
  std::string codec;
  int width = 0, height = 0, frames = 0;
  bool closed = false;
  cv::Mat bgr;
};

namespace {

struct Candidate {
  const char* fourcc;
  const char* extension;  // nullptr: keep the caller's path
  int backend;
};

// H.264 first (what browsers and hospital viewers play), the FFmpeg built-in MPEG-4 encoder
// next, and Motion-JPEG, which OpenCV's own backend writes when FFmpeg is missing, last.
constexpr Candidate kCandidates[] = {
    {"avc1", nullptr, cv::CAP_FFMPEG}, {"mp4v", nullptr, cv::CAP_FFMPEG}, {"MJPG", ".avi", cv::CAP_ANY}};

}  // namespace

VideoWriter::VideoWriter(const std::filesystem::path& path, int width, int height, double fps)
    : state_(std::make_unique<State>()) {
  if (width <= 0 || height <= 0 || !(fps > 0) || !std::isfinite(fps)) {
    FailInvalid("video " + path.string() + ": size " + std::to_string(width) + "x" + std::to_string(height) +
                " at " + std::to_string(fps) + " fps is not positive");
  }
  state_->width = width;
  state_->height = height;
  state_->bgr.create(height, width, CV_8UC3);
  for (const Candidate& c : kCandidates) {
    std::filesystem::path target = path;
    if (c.extension != nullptr) target.replace_extension(c.extension);
    const int fourcc = cv::VideoWriter::fourcc(c.fourcc[0], c.fourcc[1], c.fourcc[2], c.fourcc[3]);
    try {
      if (state_->writer.open(target.string(), c.backend, fourcc, fps, cv::Size(width, height))) {
        state_->path = target;
        state_->codec = c.fourcc;
        return;
      }
    } catch (const cv::Exception&) {
      // This encoder is not available in the installed OpenCV/FFmpeg build; try the next one.
    }
  }
  Fail(ErrorCode::kUnavailable,
       "video " + path.string() + ": no encoder could open it (tried avc1, mp4v, MJPG)");
}

VideoWriter::~VideoWriter() { Close(); }

void VideoWriter::Write(std::span<const float> rgb) {
  if (state_->closed)
    Fail(ErrorCode::kFailedPrecondition, "video " + state_->path.string() + ": write after close");
  CheckImageSize(rgb.size(), state_->width, state_->height, 3,
                 "video " + state_->path.string() + " frame " + std::to_string(state_->frames));
  auto* out = state_->bgr.ptr<std::uint8_t>(0);
  for (std::size_t p = 0; p < rgb.size() / 3; ++p) {
    for (int c = 0; c < 3; ++c) out[3 * p + c] = ToByte(rgb[3 * p + 2 - c]);  // OpenCV wants BGR
  }
  state_->writer.write(state_->bgr);
  ++state_->frames;
}

void VideoWriter::Close() {
  if (state_ == nullptr || state_->closed) return;
  state_->writer.release();
  state_->closed = true;
}

const std::filesystem::path& VideoWriter::path() const { return state_->path; }
const std::string& VideoWriter::codec() const { return state_->codec; }
int VideoWriter::frames_written() const { return state_->frames; }

}  // namespace endorecon::eval
