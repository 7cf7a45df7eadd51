#include "worker/runtime/preview_png.h"

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "common/error.h"

namespace endorecon::worker {

v1::Preview EncodePreview(const eval::Preview& preview, int iteration) {
  if (preview.channels != 1 && preview.channels != 3) {
    FailInvalid("preview '" + preview.kind + "' has " + std::to_string(preview.channels) + " channels");
  }
  if (preview.pixels.size() != static_cast<std::size_t>(preview.width * preview.height * preview.channels)) {
    FailInvalid("preview '" + preview.kind + "' has " + std::to_string(preview.pixels.size()) +
                " bytes for " + std::to_string(preview.width) + "x" + std::to_string(preview.height));
  }
  cv::Mat image(preview.height, preview.width, preview.channels == 3 ? CV_8UC3 : CV_8UC1,
                const_cast<std::uint8_t*>(preview.pixels.data()));
  cv::Mat bgr;
  if (preview.channels == 3) {
    cv::cvtColor(image, bgr, cv::COLOR_RGB2BGR);
  } else {
    bgr = image;
  }
  std::vector<std::uint8_t> png;
  cv::imencode(".png", bgr, png);
  v1::Preview out;
  out.set_kind(preview.kind);
  out.set_frame(preview.frame);
  out.set_iteration(iteration);
  out.set_png(png.data(), png.size());
  return out;
}

}  // namespace endorecon::worker
