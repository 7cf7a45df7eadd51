#include "worker/engine/scene/image_file.h"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "common/error.h"
#include "common/image_bytes.h"

namespace endorecon::scene {

namespace fs = std::filesystem;

cv::Mat DecodeImageFile(const fs::path& path) {
  CheckImageBytes(path);
  cv::Mat image;
  try {
    image = cv::imread(path.string(), cv::IMREAD_UNCHANGED);
  } catch (const cv::Exception& e) {
    // OpenCV asserts on a header declaring a size over its limits (tests/fuzz/image_decode_fuzz.cc).
    if (e.err.find("CV_IO_MAX_IMAGE_PIXELS") != std::string::npos) {
      Fail(ErrorCode::kInvalidArgument,
           path.string() +
               ": the image's header declares more pixels than can be decoded (over 2^30; a clip's "
               "frames may have at most 4096 x 4096)");
    }
    FailInvalid(path.string() + ": cannot decode the image (" + e.err + ")");
  }
  if (image.empty()) {
    FailInvalid(path.string() + ": cannot decode the image (unreadable, truncated or not an image)");
  }
  return image;
}

cv::Mat ToBgr8(const cv::Mat& image) {
  cv::Mat bgr = image;
  if (image.depth() == CV_16U) image.convertTo(bgr, CV_8U, 1.0 / 257);
  if (bgr.channels() == 1) cv::cvtColor(bgr, bgr, cv::COLOR_GRAY2BGR);
  if (bgr.channels() == 4) cv::cvtColor(bgr, bgr, cv::COLOR_BGRA2BGR);
  return bgr;
}

cv::Mat DecodeImageFileAsBgr8(const fs::path& path) {
  const cv::Mat image = DecodeImageFile(path);
  if ((image.depth() != CV_8U && image.depth() != CV_16U) || image.channels() == 2)
    FailInvalid(path.string() + ": not an 8- or 16-bit grey or colour image");
  return ToBgr8(image);
}

}  // namespace endorecon::scene
