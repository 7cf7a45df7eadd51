#include "worker/engine/scene/frame_reader.h"

#include <spdlog/spdlog.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <exception>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "common/error.h"
#include "common/npy.h"
#include "worker/engine/scene/alpha_composite.h"
#include "worker/engine/scene/clip_checks.h"
#include "worker/engine/scene/image_file.h"

namespace endorecon::scene {
namespace {

namespace fs = std::filesystem;

void CheckSize(const fs::path& path, int found_width, int found_height, int width, int height) {
  if (found_width != width || found_height != height) {
    FailInvalid(path.string() + ": size " + SizeText(found_width, found_height) +
                " differs from the clip's " + SizeText(width, height));
  }
}

void CheckSingleChannel(const fs::path& path, const cv::Mat& image, const char* what) {
  if (image.channels() != 1) {
    FailInvalid(path.string() + ": a " + what + " must have one channel, found " +
                std::to_string(image.channels()));
  }
}

// "{0, 17, 255}" (at most 8 values, then "...").
std::string ValuesText(const std::array<std::size_t, 256>& histogram) {
  std::string text = "{";
  int listed = 0, distinct = 0;
  for (int value = 0; value < 256; ++value) {
    if (histogram[value] == 0) continue;
    ++distinct;
    if (listed < 8) {
      text += (listed++ > 0 ? ", " : "") + std::to_string(value);
    }
  }
  if (distinct > listed) text += ", ... (" + std::to_string(distinct) + " distinct)";
  return text + "}";
}

std::vector<std::uint8_t> ReadMask(const fs::path& path, const FrameReadOptions& options, int width,
                                   int height) {
  const cv::Mat image = DecodeImageFile(path);
  CheckSingleChannel(path, image, "mask");
  if (image.depth() != CV_8U) FailInvalid(path.string() + ": a mask must be 8-bit with values 0 and 255");
  CheckSize(path, image.cols, image.rows, width, height);
  std::array<std::size_t, 256> histogram{};
  std::vector<std::uint8_t> mask(static_cast<std::size_t>(width) * height);
  for (int y = 0; y < height; ++y) {
    const std::uint8_t* row = image.ptr<std::uint8_t>(y);
    for (int x = 0; x < width; ++x) {
      ++histogram[row[x]];
      mask[static_cast<std::size_t>(y) * width + x] = row[x] == options.tool_value ? 1 : 0;
    }
  }
  if (histogram[0] + histogram[255] != mask.size()) {
    FailInvalid(path.string() + ": a mask must hold only 0 and 255, found values " + ValuesText(histogram));
  }
  return mask;
}

std::vector<float> ReadDepth(const fs::path& path, const FrameReadOptions& options, int width, int height) {
  std::vector<double> raw;
  if (HasExtension(path, {".npy"})) {
    const NpyArray array = ReadNpy(path);
    const bool matches = array.shape.size() == 2 || (array.shape.size() == 3 && array.shape[2] == 1);
    if (!matches || array.shape[0] != static_cast<std::size_t>(height) ||
        array.shape[1] != static_cast<std::size_t>(width)) {
      std::string shape;
      for (std::size_t dim : array.shape) shape += (shape.empty() ? "" : ", ") + std::to_string(dim);
      FailInvalid(path.string() + ": depth array of shape (" + shape + ") does not match the clip's " +
                  SizeText(width, height) + " (expected (" + std::to_string(height) + ", " +
                  std::to_string(width) + "))");
    }
    raw = array.data;
  } else {
    const cv::Mat image = DecodeImageFile(path);
    CheckSingleChannel(path, image, "depth map");
    CheckSize(path, image.cols, image.rows, width, height);
    cv::Mat values;
    image.convertTo(values, CV_64F);
    raw.assign(values.begin<double>(), values.end<double>());
  }
  std::vector<float> depth(raw.size());
  for (std::size_t i = 0; i < raw.size(); ++i) {
    if (!std::isfinite(raw[i]) || raw[i] < 0) {
      const std::size_t x = i % width, y = i / width;
      FailInvalid(path.string() + ": depth must be finite and non-negative, found " + std::to_string(raw[i]) +
                  " at pixel (" + std::to_string(x) + ", " + std::to_string(y) + ")");
    }
    depth[i] = static_cast<float>(raw[i] * options.depth_scale);
  }
  return depth;
}

std::vector<std::uint8_t> ReadRgb(const fs::path& path, const FrameReadOptions& options, int width, int height,
                                  std::atomic<bool>& transparent) {
  RgbImage image = ReadRgbImage(path, options.alpha_background);
  CheckSize(path, image.width, image.height, width, height);
  if (image.transparent) transparent = true;
  return std::move(image.rgb);
}

void CheckAllOrNone(const std::vector<FrameFiles>& frames, fs::path FrameFiles::*part, const char* what) {
  const bool first = !(frames.front().*part).empty();
  for (std::size_t i = 0; i < frames.size(); ++i) {
    if ((frames[i].*part).empty() == first) {
      FailInvalid("frame " + std::to_string(i) + " (" + frames[i].image.string() + ") " +
                  (first ? "has no " : "has a ") + what + " while frame 0 " +
                  (first ? "has one" : "has none"));
    }
  }
}

// What one pixel of a frame takes decoded (clip.h): colour 3 bytes, depth a float, each mask a byte,
// a right eye 3 bytes.
double DecodedBytesPerPixel(const FrameFiles& frame) {
  return 3.0 + (frame.depth.empty() ? 0 : 4.0) + (frame.tool_mask.empty() ? 0 : 1.0) +
         (frame.eval_mask.empty() ? 0 : 1.0) + (frame.right_image.empty() ? 0 : 3.0);
}

// A clip that cannot fit in memory is refused before its frames are decoded: decoding it was a
// worker's death by the kernel's OOM killer, its job retried on the next worker to the same end.
void CheckMemory(const FrameFiles& first, std::size_t n, const FrameReadOptions& options, const Clip& clip) {
  if (options.memory_bytes == 0) return;
  const double frame_pixels = double(clip.width) * double(clip.height);
  const double decoded = frame_pixels * (DecodedBytesPerPixel(first) + options.extra_bytes_per_pixel);
  const double per_frame =
      decoded + frame_pixels * (options.run_bytes_per_pixel +
                                (first.depth.empty() ? 0.0 : options.run_bytes_per_depth_pixel));
  const double available = double(options.memory_bytes);
  if (double(n) * per_frame <= available) return;
  constexpr double kGib = double(1 << 30);
  Fail(ErrorCode::kResourceExhausted,
       fmt::format(
           "{}: {} frames of {}x{} need about {:.1f} GiB of memory to reconstruct ({:.1f} GiB of it "
           "the decoded frames, the rest what training and evaluation keep beside them), and this "
           "machine has {:.1f} GiB available: about {} frames of this size fit. Use fewer frames "
           "(--frames START:END:STEP), smaller ones (a recording's with --size WxH), or a machine with more "
           "memory",
           clip.source, n, clip.width, clip.height, double(n) * per_frame / kGib, double(n) * decoded / kGib,
           available / kGib, std::size_t(available / per_frame)));
}

}  // namespace

RgbImage ReadRgbImage(const fs::path& path, const std::array<std::uint8_t, 3>& background) {
  cv::Mat image = DecodeImageFile(path);
  bool transparent = false;
  if (image.depth() == CV_16U) image.convertTo(image, CV_8U, 1.0 / 257.0);
  if (image.depth() != CV_8U) FailInvalid(path.string() + ": colour images must be 8- or 16-bit");
  switch (image.channels()) {
    case 1:
      cv::cvtColor(image, image, cv::COLOR_GRAY2RGB);
      break;
    case 3:
      cv::cvtColor(image, image, cv::COLOR_BGR2RGB);
      break;
    case 4: {
      cv::Mat rgba, rgb(image.rows, image.cols, CV_8UC3);
      cv::cvtColor(image, rgba, cv::COLOR_BGRA2RGBA);  // continuous, as rgb is
      transparent = CompositeRgbaOnto(rgba.data, rgba.total(), background, rgb.data);
      image = rgb;
      break;
    }
    default:
      FailInvalid(path.string() + ": colour images must have 1, 3 or 4 channels, found " +
                  std::to_string(image.channels()));
  }
  RgbImage result{image.cols, image.rows, {}, transparent};
  result.rgb.assign(image.data, image.data + image.total() * 3);  // cvtColor's output is continuous
  return result;
}

void ReadFrames(const std::vector<FrameFiles>& frames, const FrameReadOptions& options, Clip& clip) {
  if (frames.empty()) FailInvalid(clip.source + ": the clip has no frames");
  CheckAllOrNone(frames, &FrameFiles::depth, "depth file");
  CheckAllOrNone(frames, &FrameFiles::tool_mask, "tool mask");
  CheckAllOrNone(frames, &FrameFiles::eval_mask, "evaluation mask");
  CheckAllOrNone(frames, &FrameFiles::right_image, "right image");

  RgbImage first;
  if (clip.width == 0 && clip.height == 0) {
    first = ReadRgbImage(frames[0].image, options.alpha_background);
    clip.width = first.width;
    clip.height = first.height;
  }
  CheckFrameLimit(clip.width, clip.height, options.max_pixels_per_frame, clip.source);

  const std::size_t n = frames.size();
  const FrameFiles& f0 = frames.front();
  CheckMemory(f0, n, options, clip);
  clip.rgb.assign(n, {});
  clip.depth.assign(f0.depth.empty() ? 0 : n, {});
  clip.tool_mask.assign(f0.tool_mask.empty() ? 0 : n, {});
  clip.eval_mask.assign(f0.eval_mask.empty() ? 0 : n, {});
  clip.right_rgb.assign(f0.right_image.empty() ? 0 : n, {});

  std::vector<std::exception_ptr> errors(n);
  std::atomic<bool> transparent = first.transparent;
  const int w = clip.width, h = clip.height;
  tbb::parallel_for(std::size_t{0}, n, [&](std::size_t i) {
    try {
      if (options.should_stop && options.should_stop())
        Fail(ErrorCode::kCancelled, clip.source + ": the clip's load was stopped");
      const FrameFiles& f = frames[i];
      clip.rgb[i] =
          (i == 0 && !first.rgb.empty()) ? std::move(first.rgb) : ReadRgb(f.image, options, w, h, transparent);
      if (!f.depth.empty()) clip.depth[i] = ReadDepth(f.depth, options, w, h);
      if (!f.tool_mask.empty()) clip.tool_mask[i] = ReadMask(f.tool_mask, options, w, h);
      if (!f.eval_mask.empty()) clip.eval_mask[i] = ReadMask(f.eval_mask, options, w, h);
      if (!f.right_image.empty()) clip.right_rgb[i] = ReadRgb(f.right_image, options, w, h, transparent);
    } catch (...) {
      errors[i] = std::current_exception();
    }
  });
  for (const std::exception_ptr& error : errors) {
    if (error) std::rethrow_exception(error);
  }
  clip.transparent = transparent;
  // Zero is "not measured" pixel by pixel; a clip whose every depth map is all zero (an exporter's
  // placeholder) has no depth at all, and is reconstructed as a clip without depth files is: no depth
  // loss or depth-guided sampling, no depth refinement, no depth metrics against zeros.
  const bool no_depth_measured = std::all_of(clip.depth.begin(), clip.depth.end(), [](const auto& frame) {
    return std::all_of(frame.begin(), frame.end(), [](float d) { return d == 0.0f; });
  });
  if (!clip.depth.empty() && no_depth_measured) {
    spdlog::warn(
        "{}: every depth map is zero (nothing measured): the clip is reconstructed without depth, "
        "as one without depth files",
        clip.source);
    clip.depth.clear();
  }
}

FrameReadOptions FrameReadOptionsOf(const LoadOptions& options) {
  FrameReadOptions read_options;
  read_options.max_pixels_per_frame = options.max_pixels_per_frame;
  read_options.memory_bytes = options.memory_bytes;
  read_options.run_bytes_per_pixel = options.run_bytes_per_pixel;
  read_options.run_bytes_per_depth_pixel = options.run_bytes_per_depth_pixel;
  read_options.extra_bytes_per_pixel = options.extra_bytes_per_pixel;
  read_options.alpha_background = options.alpha_background;
  read_options.should_stop = options.should_stop;
  return read_options;
}

}  // namespace endorecon::scene
