// Image files as the clip loaders decode them (scene::ReadFrames): the input as a frame's colour
// image, as its depth map and as its tool mask (beside a valid 4x3 colour image). What is accepted
// has the clip's size, masks hold 0/1, depths are finite and non-negative.
#include <cmath>
#include <opencv2/imgcodecs.hpp>

#include "tests/fuzz/fuzz_input.h"
#include "worker/engine/scene/frame_reader.h"

namespace {

using namespace endorecon;

const std::filesystem::path& ValidImage() {
  static const std::filesystem::path path = [] {
    const auto file = fuzz::ScratchDir() / "valid.png";
    cv::imwrite(file.string(), cv::Mat(3, 4, CV_8UC3, cv::Scalar(10, 200, 30)));
    return file;
  }();
  return path;
}

void Read(const FrameFiles& files, const std::filesystem::path& input) {
  scene::Clip clip;
  clip.source = "fuzz clip";
  if (!fuzz::Accepts([&] { scene::ReadFrames({files}, {}, clip); },
                     {ErrorCode::kInvalidArgument, ErrorCode::kResourceExhausted}, input.string())) {
    return;
  }
  const std::size_t pixels = static_cast<std::size_t>(clip.width) * static_cast<std::size_t>(clip.height);
  if (clip.rgb.size() != 1 || clip.rgb[0].size() != 3 * pixels) fuzz::Broken("colour of the wrong size");
  for (const auto& mask : clip.tool_mask) {
    if (mask.size() != pixels) fuzz::Broken("mask of the wrong size");
    for (const auto value : mask) {
      if (value > 1) fuzz::Broken("mask value other than 0 or 1");
    }
  }
  for (const auto& depth : clip.depth) {
    if (depth.size() != pixels) fuzz::Broken("depth of the wrong size");
    for (const float z : depth) {
      if (!std::isfinite(z) || z < 0) fuzz::Broken("depth not finite or negative");
    }
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto input = fuzz::WriteInput("input.png", fuzz::Bytes(data, size));
  Read({.image = input}, input);
  Read({.image = ValidImage(), .depth = input}, input);
  Read({.image = ValidImage(), .tool_mask = input}, input);
  return 0;
}
