// The rendered sequence as a video file (video.mp4 in a results folder).
#pragma once

#include <filesystem>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace endorecon::eval {

// Streams frames into a video so a clip never has to sit in memory whole.
// Codec choice, first that the installed FFmpeg can encode: H.264 ('avc1', plays in browsers),
// then MPEG-4 Part 2 ('mp4v'), both in the .mp4 container at `path`; failing both, Motion-JPEG
// in an .avi beside it (`path` with its extension replaced), which OpenCV writes without FFmpeg.
// path() and codec() say what was written.
class VideoWriter {
 public:
  // Opens the file for width x height frames at `fps` frames per second. Throws InvalidArgument
  // on a non-positive size or rate, Error(kUnavailable) when no codec can open the file.
  VideoWriter(const std::filesystem::path& path, int width, int height, double fps);
  ~VideoWriter();  // closes the file
  VideoWriter(const VideoWriter&) = delete;
  VideoWriter& operator=(const VideoWriter&) = delete;

  // Appends one float RGB frame (width*height*3, [0, 1], clamped and rounded to 8 bits).
  // Throws InvalidArgument on a size mismatch, FailedPrecondition after Close().
  void Write(std::span<const float> rgb);

  // Finishes the file (trailer written); further writes are refused. Idempotent.
  void Close();

  const std::filesystem::path& path() const;
  const std::string& codec() const;  // "avc1", "mp4v" or "MJPG"
  int frames_written() const;

 private:
  struct State;
  std::unique_ptr<State> state_;
};

}  // namespace endorecon::eval
