// A DICOM recording turned into the engine's clip before a reconstruction, and what the results
// need to know about it afterwards (the study and the frames' times, for dicom_results.h).
//
// Mono recordings become the transforms.json layout (the recording's frame times per frame,
// EndoNeRF's field of view f = 0.8898 W, near 40 and far 130 nominal millimetres: a recording
// carries no calibration, so depth has no absolute scale), the endoscope turning about its tip
// as estimated from the frames (prepare/camera_rotation.h) or, with Endoscope::kFixed, still. Stereo
// recordings become the EndoNeRF layout with images_right/ (times evenly spaced, as that layout has them)
// and, where the eyes can be matched, a depth prior from the recording preparation (worker/prepare) treating
// them as a rectified pair with that focal length and the loader's default baseline, and the
// endoscope's poses estimated there unless Endoscope::kFixed (frames it cannot place are left out).
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "common/dicom/recording.h"
#include "common/dicom/study_context.h"

namespace endorecon::worker {

struct RecordingClip {
  std::filesystem::path clip_dir;
  dicom::StudyContext study;
  std::vector<double> times_s;  // per clip frame, seconds from the first
  std::string summary;          // what was read (SOP class, syntax, frames, where the times came from)
};

// When `input` is a DICOM recording (a file, or a folder with DICOM files at its top), reads it and
// writes the clip into `clip_dir` (replaced), plus `recording.json` beside the frames (what was read,
// the window, the times; never patient data). Returns nullopt for any other input. Throws as
// dicom::ReadRecording.
std::optional<RecordingClip> ClipFromRecording(const std::filesystem::path& input,
                                               const dicom::RecordingOptions& options,
                                               const std::filesystem::path& clip_dir);

}  // namespace endorecon::worker
