#include "common/dicom/recording_header.h"

#include <fmt/format.h>

#include <cmath>

#include "common/dicom/recording_series.h"
#include "common/error.h"

namespace endorecon::dicom {

RecordingShape CheckRecordingHeader(const std::filesystem::path& path, StereoLayout stereo,
                                    const FrameRange& window, FrameSize size) {
  const auto series = LoadSeriesHeaders(path);
  CheckSeriesFitLayout(series, stereo, path);
  const InstanceHeader& first = series.front().front();
  RecordingShape shape;
  shape.frames = SeriesFrames(series.front());
  shape.eye = EyeSize(stereo, first.columns, first.rows, path.string());
  CheckWindowHoldsFrames(window, shape.frames, path.string());
  CheckSameShape(size, shape.eye);
  return shape;
}

void CheckWindowHoldsFrames(const FrameRange& window, int frames, const std::string& where) {
  if (!window.Of(frames).empty()) return;
  FailInvalid(where + ": zero frames: the window " + window.ToString() + " holds none of the recording's " +
              std::to_string(frames) + " frames");
}

void CheckSameShape(FrameSize size, FrameSize recorded) {
  if (size.width <= 0 || size.height <= 0) return;
  const double change = (double(size.width) / size.height) / (double(recorded.width) / recorded.height);
  if (std::abs(change - 1) <= 0.01) return;
  const int height = 2 * static_cast<int>(std::lround(size.width * recorded.height / (2.0 * recorded.width)));
  FailInvalid(fmt::format("size {}x{} changes the recording's {}x{} aspect ratio; give a size of the same "
                          "shape, e.g. {}x{}",
                          size.width, size.height, recorded.width, recorded.height, size.width, height));
}

}  // namespace endorecon::dicom
