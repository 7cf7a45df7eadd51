// DICOM recordings as the worker reads them (dicom::ReadRecording on one file): whatever the file
// holds, an accepted recording has frames of one size with one time each, non-decreasing.
#include <opencv2/core.hpp>

#include "common/dicom/dcmtk_logging.h"
#include "common/dicom/recording.h"
#include "tests/fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace endorecon;
  static const bool quiet = [] {
    dicom::QuietDcmtkLogs();
    return true;
  }();
  (void)quiet;
  const auto path = fuzz::WriteInput("recording.dcm", fuzz::Bytes(data, size));
  dicom::Recording recording;
  if (!fuzz::Accepts([&] { recording = dicom::ReadRecording(path, {}); },
                     {ErrorCode::kInvalidArgument, ErrorCode::kResourceExhausted}, path.string())) {
    return 0;
  }
  if (recording.left.empty() || recording.times_s.size() != recording.left.size())
    fuzz::Broken("accepted a recording whose frames and times disagree");
  for (std::size_t i = 0; i < recording.left.size(); ++i) {
    const cv::Mat& frame = recording.left[i];
    if (frame.type() != CV_8UC3 || frame.size() != recording.left[0].size() || frame.empty())
      fuzz::Broken("accepted frames that are not 8-bit BGR of one size");
    if (i > 0 && !(recording.times_s[i] >= recording.times_s[i - 1])) fuzz::Broken("times that go back");
  }
  return 0;
}
