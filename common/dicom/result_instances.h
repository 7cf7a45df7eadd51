// The DICOM instances of a reconstruction's results, each a new series in the study of
// `SeriesHeader::study`:
//   WriteColorFrames  Multi-frame True Color Secondary Capture (8-bit RGB, uncompressed)
//   WriteScalarFrames Multi-frame Grayscale Word Secondary Capture (16-bit) with Rescale Slope and
//                     Intercept giving the value in `units` (stored = round(value / slope))
//   WriteStlMesh      Encapsulated STL Storage (a binary STL file, as it is)
// Each carries the patient and study modules copied from the source, a Derivation Description,
// references to the source series (Referenced Series Sequence, Source Image Sequence) and new
// Series and SOP Instance UIDs under `uid_root`. Files are Part 10, Explicit VR Little Endian.
// Every writer throws Error(kUnavailable) naming the file when it cannot be written and
// InvalidArgument when the frames are empty or differ in size.
#pragma once

#include <filesystem>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "common/dicom/study_context.h"

namespace endorecon::dicom {

struct SeriesHeader {
  StudyContext study;
  std::string uid_root;                // "" : UUID-derived UIDs (2.25...)
  int series_number = 900;             // Series Number of the new series
  std::string series_description;      // e.g. "endorecon rendered frames"
  std::string derivation_description;  // what made the instance (method, software, source)
  std::string frame_of_reference_uid;  // shared by the instances of one result set
  std::vector<double> frame_times_s;   // one per frame (seconds from the first); empty: 15 frames/s
};

struct ScalarUnits {
  std::string rescale_type;  // Rescale Type (0028,1054): the unit, at most 64 characters
  std::string description;   // what the values are, in the instance's Image Comments
};

// `frames`: 8-bit BGR (OpenCV's order), one size. Returns the SOP Instance UID.
std::string WriteColorFrames(const std::filesystem::path& file, const SeriesHeader& header,
                             const std::vector<cv::Mat>& frames);

// `frames`: width*height floats each, row-major. Non-finite and negative values are stored as 0;
// the slope is the largest finite value / 65535 (1 when there is none), the intercept 0.
std::string WriteScalarFrames(const std::filesystem::path& file, const SeriesHeader& header,
                              const std::vector<std::vector<float>>& frames, int width, int height,
                              const ScalarUnits& units);

// `stl`: the bytes of a binary STL file; `unit`: the length unit of its coordinates as a UCUM code
// ("mm"). Returns the SOP Instance UID.
std::string WriteStlMesh(const std::filesystem::path& file, const SeriesHeader& header,
                         const std::string& stl, const std::string& unit);

}  // namespace endorecon::dicom
