#include "worker/runtime/dicom_job.h"

#include <spdlog/spdlog.h>

#include "common/prepare_flags.h"
#include "worker/runtime/dicom_results.h"

namespace endorecon::worker {

dicom::RecordingOptions RecordingOptionsOf(const v1::RecordingOptions& options) {
  dicom::RecordingOptions out;
  out.stereo = dicom::ParseStereoLayout(options.stereo());
  out.frames = dicom::ParseFrameWindow(options.frames());
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
  return ClipFromRecording(input, RecordingOptionsOf(options), clip_dir);
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
