// A DICOM recording read into frames and times: what the worker turns into the engine's clip.
//
// Read: Video Endoscopic (and Video Photographic) Image Storage with an MPEG-2 or MPEG-4 AVC/H.264
// (or HEVC) transfer syntax, whose encapsulated stream DCMTK extracts and FFmpeg (OpenCV videoio)
// decodes; and true-colour or grey images, single- or multi-frame (VL Endoscopic, Secondary
// Capture, Multi-frame True Color / Grayscale Byte Secondary Capture), uncompressed, RLE or JPEG,
// decoded by DCMTK. A recording is one file, or a folder of files: one series (its instances in
// Instance Number order, frames concatenated), or two series for stereo (the lower Series Number
// is the left eye).
#pragma once

#include <filesystem>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "common/dicom/recording_layout.h"
#include "common/dicom/study_context.h"
#include "common/prepare_flags.h"

namespace endorecon::dicom {

struct RecordingOptions {
  StereoLayout stereo = StereoLayout::kMono;
  FrameRange frames;   // applied first, on the recording's frame indices
  double fps = 0;      // > 0: then keep at most this many frames per second of recording time
  Endoscope endoscope = Endoscope::kMoving;  // not read here: for the clip made from it
  cv::Size size;                             // not read here: the clip's frame size (empty: as recorded)
};

struct Recording {
  std::vector<cv::Mat> left;    // 8-bit BGR (OpenCV's order), one per kept frame
  std::vector<cv::Mat> right;   // the right eye, same count, when stereo; else empty
  std::vector<double> times_s;  // per kept frame, seconds from the recording's first frame
  std::vector<int> frame_numbers;  // per kept frame, its number in the recording (0-based)
  std::string times_from;       // which attribute gave the times (for the clip's record)
  int recording_frames = 0;     // frames in the recording before the window
  StudyContext study;           // the left (or only) series' patient, study and instances
  std::string description;      // SOP class, transfer syntax, size: safe to log (no patient data)
};

// Reads `path` (a DICOM file, or a folder whose DICOM files are the recording; other files in it
// are ignored). Throws InvalidArgument naming the file (and frame) for: not DICOM, a SOP class or
// transfer syntax it cannot use, a truncated or undecodable pixel stream, zero frames (after the
// window too), a stereo layout the frames do not fit; kNotFound when `path` does not exist.
Recording ReadRecording(const std::filesystem::path& path, const RecordingOptions& options);

}  // namespace endorecon::dicom
