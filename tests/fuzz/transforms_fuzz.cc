// transforms.json as the loader reads it (scene::LoadTransformsClip), in a clip folder that holds
// two 4x3 images, a depth map of each kind and a mask for the file to name. An accepted clip has
// one camera and one time per frame, times in [0, 1], and finite bounds.
#include <cmath>
#include <opencv2/imgcodecs.hpp>

#include "common/npy.h"
#include "tests/fuzz/fuzz_input.h"
#include "worker/engine/scene/transforms_loader.h"

namespace {

// The files the seeds name (tests/fuzz/fuzz_seed_maker.cc writes the matching transforms.json).
std::filesystem::path ClipDir() {
  static const std::filesystem::path dir = [] {
    const auto root = endorecon::fuzz::ScratchDir() / "clip";
    std::filesystem::create_directories(root / "images");
    cv::imwrite((root / "images/a.png").string(), cv::Mat(3, 4, CV_8UC3, cv::Scalar(10, 200, 30)));
    cv::imwrite((root / "images/b.jpg").string(), cv::Mat(3, 4, CV_8UC3, cv::Scalar(90, 20, 130)));
    cv::imwrite((root / "mask.png").string(), cv::Mat(3, 4, CV_8UC1, cv::Scalar(255)));
    cv::imwrite((root / "depth.png").string(), cv::Mat(3, 4, CV_16UC1, cv::Scalar(1200)));
    const float depth[12] = {1, 1, 1, 1, 2, 2, 2, 2, 3, 3, 3, 0};
    endorecon::WriteNpyFloat32(root / "depth.npy", depth, {3, 4});
    return root;
  }();
  return dir;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace endorecon;
  const auto dir = ClipDir();
  fuzz::WriteInput("clip/transforms.json", fuzz::Bytes(data, size));
  scene::Clip clip;
  if (!fuzz::Accepts([&] { clip = scene::LoadTransformsClip(dir, {}); },
                     {ErrorCode::kInvalidArgument, ErrorCode::kResourceExhausted}, dir.string())) {
    return 0;
  }
  const std::size_t n = clip.rgb.size();
  if (n == 0 || clip.cameras.size() != n || clip.times.size() != n) fuzz::Broken("frame counts disagree");
  for (const float t : clip.times) {
    if (!(t >= 0 && t <= 1)) fuzz::Broken("a time outside [0, 1]");
  }
  if (!std::isfinite(clip.near) || !std::isfinite(clip.far) || !(clip.near < clip.far))
    fuzz::Broken("bounds that are not finite and ordered");
  return 0;
}
