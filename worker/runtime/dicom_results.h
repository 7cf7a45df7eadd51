// A results folder's DICOM: dicom/rendered.dcm (the rendered frames, Multi-frame True Color
// Secondary Capture), dicom/depth.dcm, dicom/uncertainty.dcm and dicom/model_map.dcm (Multi-frame
// Grayscale Word Secondary Capture with Rescale Slope/Intercept), dicom/mesh.dcm (Encapsulated STL of
// mesh.stl), each a new series of the source's study (or of a new study when the input was not DICOM).
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "common/dicom/study_context.h"

namespace endorecon::worker {

struct DicomResultSettings {
  dicom::StudyContext study;    // the recording's, or dicom::NewStudyContext(...)
  std::vector<double> times_s;  // per frame, from the recording; empty: 15 frames per second
  std::string uid_root;
  std::string source_summary;  // what the input was (no patient data), for the Derivation Description
};

// Reads rgb/*.png, depth/*.npy, uncertainty/*.npy (total) and mesh.stl from `results_dir` and writes
// the instances into results_dir/dicom/. Returns the files written. Throws InvalidArgument naming
// the file for a missing or malformed result file, Error(kUnavailable) when one cannot be written.
std::vector<std::filesystem::path> WriteDicomResults(const std::filesystem::path& results_dir,
                                                     const DicomResultSettings& settings);

}  // namespace endorecon::worker
