#include "worker/runtime/synth_texture.h"

#include <algorithm>
#include <filesystem>
#include <opencv2/imgproc.hpp>

#include "common/clip_files.h"
#include "common/error.h"
#include "worker/engine/scene/frame_reader.h"
#include "worker/prepare/frame_source.h"

namespace endorecon::worker {
namespace {

// Fraction of the shorter side kept from the centre of a recording's frame: endoscopes see a
// circle (black corners), and its centre is tissue.
constexpr double kTextureCrop = 0.7;

}  // namespace

void LoadSynthTexture(const std::string& path, int index, scene::SynthOptions& options) {
  if (std::filesystem::is_regular_file(path) && HasExtension(path, ImageExtensions())) {
    scene::RgbImage image = scene::ReadRgbImage(path);
    options.texture = std::move(image.rgb);
    options.texture_width = image.width;
    options.texture_height = image.height;
    options.texture_source = path;
    return;
  }
  auto source = prepare::OpenFrameSource(path);
  const int announced = source->announced_frames();
  const int wanted = index >= 0 ? index : std::max(0, announced / 2);
  prepare::SourceFrame frame;
  for (int i = 0; i < wanted; ++i) {
    if (!source->Skip()) {
      FailInvalid(path + ": has no frame " + std::to_string(wanted) + " (it ended after " + std::to_string(i) +
                  ")");
    }
  }
  if (!source->Next(frame)) FailInvalid(path + ": has no frame " + std::to_string(wanted));
  const int side = int(kTextureCrop * std::min(frame.image.cols, frame.image.rows));
  const cv::Rect centre((frame.image.cols - side) / 2, (frame.image.rows - side) / 2, side, side);
  cv::Mat rgb;
  cv::cvtColor(frame.image(centre), rgb, cv::COLOR_BGR2RGB);
  options.texture.assign(rgb.data, rgb.data + rgb.total() * 3);  // cvtColor's output is continuous
  options.texture_width = side;
  options.texture_height = side;
  options.texture_source =
      path + " frame " + std::to_string(wanted) + " (centre " + std::to_string(side) + " px square)";
}

}  // namespace endorecon::worker
