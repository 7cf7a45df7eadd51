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
  CheckFrameFits(size, shape.eye, path.string());
  return shape;
}

void CheckWindowHoldsFrames(const FrameRange& window, int frames, const std::string& where) {
  if (!window.Of(frames).empty()) return;
  FailInvalid(where + ": zero frames: the window " + window.ToString() + " holds none of the recording's " +
              std::to_string(frames) + " frames");
}

namespace {

bool KeepsShape(int width, int height, FrameSize recorded) {
  const double change = (double(width) / height) / (double(recorded.width) / recorded.height);
  return std::abs(change - 1) <= 0.01;
}

// The even size nearest `width` wide that keeps `recorded`'s shape: the height rounded to even alone
// could miss it (64 wide for 48x32 gave 64x42, itself refused; found 2026-12-07). Twice the recorded
// size keeps it exactly, so the search ends.
FrameSize SameShapeNear(int width, FrameSize recorded) {
  for (int step = 0;; step += 2) {
    for (const int w : {width - step, width + step}) {
      const int h = 2 * static_cast<int>(std::lround(w * recorded.height / (2.0 * recorded.width)));
      if (w >= 2 && h >= 2 && KeepsShape(w, h, recorded)) return {w, h};
    }
  }
}

}  // namespace

// Frames of 4200x4200 were uploaded, queued and decoded, then refused naming the worker's own
// "clip-from-dicom/transforms.json" and no --size (found 2026-12-07).
void CheckFrameFits(FrameSize size, FrameSize recorded, const std::string& where) {
  const double pixels = double(recorded.width) * double(recorded.height);
  if ((size.width > 0 && size.height > 0) || pixels <= kMostFramePixels) return;
  const double scale = std::sqrt(kMostFramePixels / pixels);
  FrameSize suggested = SameShapeNear(2 * static_cast<int>(recorded.width * scale / 2), recorded);
  while (double(suggested.width) * suggested.height > kMostFramePixels && suggested.width > 2)
    suggested = SameShapeNear(suggested.width - 2, recorded);
  FailInvalid(fmt::format(
      "{}: frames of {}x{} ({:.0f} pixels) are larger than a clip's frame may be ({:.0f} pixels, 4096 x "
      "4096); give --size to scale them, e.g. --size {}x{}",
      where, recorded.width, recorded.height, pixels, kMostFramePixels, suggested.width, suggested.height));
}

void CheckSameShape(FrameSize size, FrameSize recorded) {
  if (size.width <= 0 || size.height <= 0 || KeepsShape(size.width, size.height, recorded)) return;
  const FrameSize suggested = SameShapeNear(size.width - size.width % 2, recorded);
  FailInvalid(fmt::format(
      "size {}x{} changes the recording's {}x{} aspect ratio; give a size of the same "
      "shape, e.g. {}x{}",
      size.width, size.height, recorded.width, recorded.height, suggested.width, suggested.height));
}

}  // namespace endorecon::dicom
