// The DICOM steps around a reconstruction, as the job's (or the command line's) options ask:
// before it, a DICOM recording becomes the engine's clip; after it, the results get dicom/.
#pragma once

#include <filesystem>
#include <optional>

#include "common/prepare_flags.h"
#include "endorecon/v1/job.pb.h"
#include "worker/runtime/recording_clip.h"

namespace endorecon::worker {

// Throws InvalidArgument naming the bad option.
dicom::RecordingOptions RecordingOptionsOf(const v1::RecordingOptions& options);

// When `input` is a DICOM recording, converts it into `clip_dir` and returns what the results need;
// nullopt for any other clip. Throws InvalidArgument naming them when `input` is a clip folder and
// `options` ask to thin or scale a recording's frames (--fps, --size, --stereo, --endoscope).
std::optional<RecordingClip> PrepareRecording(const std::filesystem::path& input,
                                              const v1::RecordingOptions& options,
                                              const std::filesystem::path& clip_dir);

// The frames of the clip to reconstruct (ReconstructOptions::frames): a clip folder's --frames (every
// frame without it); every frame of a clip made from a `recording`, whose window its making applied.
FrameRange ClipFolderFrames(const std::optional<RecordingClip>& recording,
                            const v1::RecordingOptions& options);

// Writes out_dir/dicom/ when the input was a recording (into its study) or `dicom.enabled()` (into
// `dicom.study_uid()`, or a new study, with the given patient), and for a recording copies the
// clip's recording.json beside the results. Does nothing otherwise.
void WriteJobDicom(const std::filesystem::path& out_dir, const std::optional<RecordingClip>& recording,
                   const v1::DicomOutputOptions& dicom);

}  // namespace endorecon::worker
