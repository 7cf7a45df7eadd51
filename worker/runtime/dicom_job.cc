#include "worker/runtime/dicom_job.h"

#include <spdlog/spdlog.h>

#include <filesystem>
#include <string>
#include <utility>

#include "common/error.h"
#include "common/prepare_flags.h"
#include "worker/runtime/dicom_results.h"

namespace endorecon::worker {

dicom::RecordingOptions RecordingOptionsOf(const v1::RecordingOptions& options) {
  dicom::RecordingOptions out;
  out.stereo = dicom::ParseStereoLayout(options.stereo());
  out.frames = ParseFrameRange(options.frames());
  out.fps = options.fps();
  out.endoscope = dicom::ParseEndoscope(options.endoscope());
  if (!options.size().empty()) {
    const FrameSize size = ParseFrameSize(options.size());
    out.size = cv::Size(size.width, size.height);
  }
  return out;
}

std::optional<RecordingClip> PrepareRecording(const std::filesystem::path& input,
                                              const v1::RecordingOptions& options,
                                              const std::filesystem::path& clip_dir) {
  auto clip = ClipFromRecording(input, RecordingOptionsOf(options), clip_dir);
  std::error_code error;
  if (!clip && std::filesystem::is_directory(input, error)) {
    // A clip folder's frames are used as they are (--frames picks some: the caller's ClipFolderFrames);
    // options that would thin or scale a recording's frames are refused rather than ignored.
    std::string given;
    for (const auto& [name, set] :
         {std::pair{"--stereo", !options.stereo().empty()}, std::pair{"--fps", options.fps() > 0},
          std::pair{"--size", !options.size().empty()},
          std::pair{"--endoscope", !options.endoscope().empty()}}) {
      if (set) given += (given.empty() ? "" : ", ") + std::string(name);
    }
    if (!given.empty()) {
      FailInvalid(given + (given.find(',') == std::string::npos ? " applies" : " apply") +
                  " to a DICOM recording, and " + input.string() +
                  " is a clip folder, whose frames are used as they are");
    }
  }
  return clip;
}

FrameRange ClipFolderFrames(const std::optional<RecordingClip>& recording,
                            const v1::RecordingOptions& options) {
  // A recording's window was applied when its clip was made.
  return recording ? FrameRange{} : ParseFrameRange(options.frames());
}

void WriteJobDicom(const std::filesystem::path& out_dir, const std::optional<RecordingClip>& recording,
                   const v1::DicomOutputOptions& dicom) {
  if (recording) {
    // How the recording was read and made into the clip (its window, size, times, the endoscope's
    // turns or poses), beside the results: the clip itself stays with the worker.
    std::filesystem::copy_file(recording->clip_dir / "recording.json", out_dir / "recording.json",
                               std::filesystem::copy_options::overwrite_existing);
  }
  if (!recording && !dicom.enabled()) return;
  DicomResultSettings settings;
  settings.uid_root = dicom.uid_root();
  if (recording) {
    settings.study = recording->study;
    settings.times_s = recording->times_s;
    settings.source_summary = recording->summary;
  } else {
    settings.study =
        dicom::NewStudyContext(dicom.patient_id(), dicom.patient_name(), dicom.study_uid(), dicom.uid_root());
  }
  const auto files = WriteDicomResults(out_dir, settings);
  spdlog::info("wrote {} DICOM instance(s) into {}", files.size(), (out_dir / "dicom").string());
}

}  // namespace endorecon::worker
