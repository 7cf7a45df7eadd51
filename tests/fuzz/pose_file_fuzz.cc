// Pose files for `prepare --poses` (prepare::ReadPoseFile): the first byte picks the format (even:
// JSON, odd: CSV), the rest is the file. An accepted file yields finite rigid poses.
#include <cmath>
#include <opencv2/core.hpp>

#include "tests/fuzz/fuzz_input.h"
#include "worker/prepare/pose_file.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace endorecon;
  if (size == 0) return 0;
  const auto path = fuzz::WriteInput(data[0] % 2 == 0 ? "poses.json" : "poses.csv", fuzz::Bytes(data + 1, size - 1));
  std::vector<cv::Matx44d> poses;
  if (!fuzz::Accepts([&] { poses = prepare::ReadPoseFile(path); }, {ErrorCode::kInvalidArgument}, path.string()))
    return 0;
  if (poses.empty()) fuzz::Broken("accepted a file without poses");
  for (const cv::Matx44d& pose : poses) {
    const cv::Matx33d r = pose.get_minor<3, 3>(0, 0);
    if (cv::norm(r.t() * r - cv::Matx33d::eye()) > 1e-2 || !(cv::determinant(r) > 0))
      fuzz::Broken("accepted a rotation that is not one");
    for (int k = 0; k < 16; ++k) {
      if (!std::isfinite(pose.val[k])) fuzz::Broken("accepted a pose that is not finite");
    }
    if (pose(3, 0) != 0 || pose(3, 1) != 0 || pose(3, 2) != 0 || pose(3, 3) != 1)
      fuzz::Broken("accepted a last row other than [0, 0, 0, 1]");
  }
  return 0;
}
