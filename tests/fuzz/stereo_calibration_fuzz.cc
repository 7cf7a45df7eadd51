// Stereo calibration files for `prepare --calibration` (prepare::LoadStereoCalibration). The first
// byte picks the form: 0 an OpenCV file as YAML, 1 as XML, 2 a ROS camera_info pair (the input is
// the left eye's file; the right eye's is a valid one of the same size), 3 the same pair with the
// input as the right eye's. An accepted calibration is finite, with positive focal lengths and a
// proper rotation.
#include <cmath>
#include <opencv2/core.hpp>

#include "tests/fuzz/fuzz_input.h"
#include "worker/prepare/stereo_calibration.h"

namespace {

// A plausible ROS camera_info of a 640x512 eye, the partner of the input in the pair forms.
constexpr char kRosEye[] = R"(image_width: 640
image_height: 512
camera_name: eye
camera_matrix: {rows: 3, cols: 3, data: [500, 0, 320, 0, 500, 256, 0, 0, 1]}
distortion_model: plumb_bob
distortion_coefficients: {rows: 1, cols: 5, data: [0, 0, 0, 0, 0]}
rectification_matrix: {rows: 3, cols: 3, data: [1, 0, 0, 0, 1, 0, 0, 0, 1]}
projection_matrix: {rows: 3, cols: 4, data: [500, 0, 320, -2500, 0, 500, 256, 0, 0, 0, 1, 0]}
)";

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace endorecon;
  if (size == 0) return 0;
  const int form = data[0] % 4;
  const auto input = fuzz::WriteInput(form == 1 ? "stereo.xml" : "stereo.yaml", fuzz::Bytes(data + 1, size - 1));
  std::vector<std::filesystem::path> files = {input};
  if (form >= 2) {
    const auto other = fuzz::WriteInput("other.yaml", kRosEye);
    files = form == 2 ? std::vector{input, other} : std::vector{other, input};
  }
  prepare::StereoCalibration calibration;
  if (!fuzz::Accepts([&] { calibration = prepare::LoadStereoCalibration(files); }, {ErrorCode::kInvalidArgument},
                     input.string())) {
    return 0;
  }
  for (const cv::Matx33d& k : {calibration.k1, calibration.k2}) {
    if (!(k(0, 0) > 0 && k(1, 1) > 0 && std::isfinite(k(0, 0)) && std::isfinite(k(1, 1))))
      fuzz::Broken("accepted a camera matrix without positive finite focal lengths");
  }
  const cv::Matx33d& r = calibration.r;
  if (cv::norm(r.t() * r - cv::Matx33d::eye()) > 1e-2 || !(cv::determinant(r) > 0))
    fuzz::Broken("accepted a rotation that is not one");
  if (!std::isfinite(cv::norm(calibration.t))) fuzz::Broken("accepted a translation that is not finite");
  for (const cv::Mat& d : {calibration.d1, calibration.d2}) {
    if (!cv::checkRange(d)) fuzz::Broken("accepted distortion that is not finite");
  }
  return 0;
}
