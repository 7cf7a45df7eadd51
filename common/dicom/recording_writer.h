// Recordings as a hospital's endoscopy system stores them, made from frames on disk: a Video
// Endoscopic Image instance wrapping an MPEG-4 AVC/H.264 file, or a multi-frame VL Endoscopic
// instance, uncompressed or JPEG baseline. For users whose recorder writes plain video, and for
// tests that need real recordings.
#pragma once

#include <filesystem>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "common/dicom/study_context.h"

namespace endorecon::dicom {

struct RecordingHeader {
  StudyContext study;      // patient and study (study.study_instance_uid required)
  std::string series_uid;  // empty: a new one
  int series_number = 1;
  std::string uid_root;  // for new UIDs
  std::string series_description = "endoscopy";
};

// Wraps `video` (an H.264 stream in an MP4, MPEG-TS or Annex B file, written e.g. by OpenCV's
// VideoWriter with fourcc avc1) as Video Endoscopic Image Storage with the transfer syntax MPEG-4
// AVC/H.264 High Profile / Level 4.1, one fragment. `frames`, `width`, `height` must describe the
// stream; `fps` gives Frame Time. Returns the SOP Instance UID. Throws InvalidArgument for a
// missing or empty video, Error(kUnavailable) when `out` cannot be written.
std::string WriteVideoEndoscopic(const std::filesystem::path& video, int frames, int width, int height,
                                 double fps, const RecordingHeader& header, const std::filesystem::path& out);

// `frames` (8-bit BGR, one size) as one multi-frame VL Endoscopic Image instance with a Frame Time
// Vector from `times_s` (seconds, one per frame, non-decreasing), uncompressed or JPEG baseline
// (one frame per fragment). Returns the SOP Instance UID.
std::string WriteEndoscopicFrames(const std::vector<cv::Mat>& frames, const std::vector<double>& times_s,
                                  bool jpeg, const RecordingHeader& header, const std::filesystem::path& out);

}  // namespace endorecon::dicom
