#include "common/recording_flags_cli.h"

#include <CLI/CLI.hpp>
#include <cstdint>
#include <string>

#include "common/cli_checks.h"

namespace endorecon {

void AddRecordingFlags(CLI::App& cmd, v1::RecordingOptions& recording) {
  cmd.add_option_function<std::string>(
         "--stereo", [&recording](const std::string& v) { recording.set_stereo(v); },
         "DICOM recording: mono (the default), side-by-side, top-bottom, or series (two series: left, right)")
      ->check(CLI::IsMember({"mono", "side-by-side", "top-bottom", "series"}));
  cmd.add_option_function<double>(
         "--fps", [&recording](double v) { recording.set_fps(v); },
         "DICOM recording: keep at most this many frames per second")
      ->check(AtLeastZero());
  cmd.add_option_function<std::string>(
         "--endoscope", [&recording](const std::string& v) { recording.set_endoscope(v); },
         "DICOM recording: moving (estimate the endoscope's motion from the frames: turns for mono, "
         "poses for stereo; the default) or fixed")
      ->check(CLI::IsMember({"moving", "fixed"}));
}

void AddDicomResultFlags(CLI::App& cmd, v1::DicomOutputOptions& dicom) {
  cmd.add_flag_function(
      "--dicom", [&dicom](std::int64_t) { dicom.set_enabled(true); },
      "DICOM results (dicom/) for a clip that is not DICOM (a DICOM recording always gets them)");
  cmd.add_option_function<std::string>(
      "--patient-id", [&dicom](const std::string& v) { dicom.set_patient_id(v); },
      "with --dicom: the patient's ID");
  cmd.add_option_function<std::string>(
      "--patient-name", [&dicom](const std::string& v) { dicom.set_patient_name(v); },
      "with --dicom: the patient's name (DICOM PN, e.g. Doe^Jane)");
  cmd.add_option_function<std::string>(
      "--study-uid", [&dicom](const std::string& v) { dicom.set_study_uid(v); },
      "with --dicom: the study the results join (default: a new study)");
}

}  // namespace endorecon
