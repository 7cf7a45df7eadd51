#include "common/dicom/rgb_pixels.h"

#include "common/error.h"

namespace endorecon::dicom {

std::vector<Uint8> InterleavedRgb(const std::vector<cv::Mat>& frames, const std::string& where) {
  if (frames.empty()) FailInvalid(where + ": no frames to write");
  const int width = frames[0].cols, height = frames[0].rows;
  const std::size_t frame_bytes = static_cast<std::size_t>(width) * height * 3;
  std::vector<Uint8> pixels(frame_bytes * frames.size());
  for (std::size_t f = 0; f < frames.size(); ++f) {
    if (frames[f].cols != width || frames[f].rows != height || frames[f].type() != CV_8UC3) {
      FailInvalid(where + ": frame " + std::to_string(f) + " differs from frame 0 in size or type");
    }
    for (int y = 0; y < height; ++y) {
      const auto* row = frames[f].ptr<cv::Vec3b>(y);
      Uint8* out = &pixels[f * frame_bytes + static_cast<std::size_t>(y) * width * 3];
      for (int x = 0; x < width; ++x) {
        out[3 * x + 0] = row[x][2];
        out[3 * x + 1] = row[x][1];
        out[3 * x + 2] = row[x][0];
      }
    }
  }
  return pixels;
}

}  // namespace endorecon::dicom
