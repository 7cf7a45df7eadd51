// poses_bounds.npy as the EndoNeRF loader reads it (scene::LoadEndoNerfClip on a folder of two
// valid 4x3 images beside the input). An accepted file yields one camera per frame, of the
// images' size, inside finite ordered bounds.
#include <cmath>
#include <opencv2/imgcodecs.hpp>

#include "tests/fuzz/fuzz_input.h"
#include "worker/engine/scene/endonerf_loader.h"

namespace {

const std::filesystem::path& ClipDir() {
  static const std::filesystem::path dir = [] {
    const auto root = endorecon::fuzz::ScratchDir() / "endonerf";
    std::filesystem::create_directories(root / "images");
    cv::imwrite((root / "images/000.png").string(), cv::Mat(3, 4, CV_8UC3, cv::Scalar(10, 200, 30)));
    cv::imwrite((root / "images/001.png").string(), cv::Mat(3, 4, CV_8UC3, cv::Scalar(90, 20, 130)));
    return root;
  }();
  return dir;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace endorecon;
  const auto& dir = ClipDir();
  fuzz::WriteInput("endonerf/poses_bounds.npy", fuzz::Bytes(data, size));
  scene::Clip clip;
  if (!fuzz::Accepts([&] { clip = scene::LoadEndoNerfClip(dir, {}); },
                     {ErrorCode::kInvalidArgument, ErrorCode::kResourceExhausted}, dir.string())) {
    return 0;
  }
  if (clip.cameras.size() != 2 || clip.rgb.size() != 2) fuzz::Broken("accepted a pose count unlike the images'");
  if (!std::isfinite(clip.near) || !std::isfinite(clip.far) || !(clip.near < clip.far))
    fuzz::Broken("accepted bounds that are not finite and ordered");
  for (const auto& camera : clip.cameras) {
    if (camera.width != 4 || camera.height != 3) fuzz::Broken("a camera of another size than the images");
    if (!std::isfinite(camera.fx) || !(camera.fx > 0)) fuzz::Broken("a focal length that is not finite and positive");
  }
  return 0;
}
