// The seam between recordings and preparation: a FrameSource hands out the frames of one
// recording in order, each an 8-bit BGR image with its time. Two kinds exist: a video file
// (anything the installed FFmpeg decodes) and a folder of images (sorted by name).
//
// To add a kind of recording (a DICOM multi-frame file, say): implement FrameSource in a file of
// its own and add its case to OpenFrameSource. Everything downstream (StereoSource's pairing and
// splitting, frame selection, masks, `prepare`, `calibrate`, the job runner) takes any FrameSource.
#pragma once

#include <filesystem>
#include <memory>
#include <opencv2/core.hpp>
#include <string>

namespace endorecon::prepare {

struct SourceFrame {
  cv::Mat image;      // 8-bit BGR (grey and 16-bit recordings are converted), owned by the frame
  double time_s = 0;  // since the recording's first frame
  int index = 0;      // 0-based position in the recording
};

class FrameSource {
 public:
  virtual ~FrameSource() = default;

  // The file or folder, as messages name it.
  virtual const std::string& name() const = 0;
  // The size of every frame (read from the first one when the source is opened).
  virtual cv::Size frame_size() const = 0;
  // How many frames the recording says it holds (a video's header, a folder's files); -1: unknown.
  virtual int announced_frames() const = 0;
  // The frame rate the recording announces (a video's header); 0: none (a folder of images).
  virtual double frame_rate() const { return 0; }
  // Whether announced_frames() is exact (a folder's files) rather than a header's, which may be an
  // estimate from the duration a frame or two off.
  virtual bool count_is_exact() const { return false; }
  // Reads the next frame into `frame`; false after the last. Throws Error(kInvalidArgument) naming
  // the source and the frame when the frame cannot be decoded, has another size, or when the
  // recording ends well before the frames it announced (a truncated file).
  virtual bool Next(SourceFrame& frame) = 0;
  // Moves past the next frame without converting it (where the format allows); false after the last.
  virtual bool Skip() {
    SourceFrame ignored;
    return Next(ignored);
  }
};

// Moves `source` past up to `count` frames; returns how many it held (fewer: it ended).
int SkipFrames(FrameSource& source, int count);

// A folder (of images, ImageExtensions) or a video file. Throws Error(kNotFound) when `path` does
// not exist, Error(kInvalidArgument) naming it when it cannot be read as either or holds no frame.
std::unique_ptr<FrameSource> OpenFrameSource(const std::filesystem::path& path);

// The time between an image folder's frames (a folder says nothing about its frame rate).
constexpr double kImageFolderFramePeriod = 1.0 / 25;

}  // namespace endorecon::prepare
