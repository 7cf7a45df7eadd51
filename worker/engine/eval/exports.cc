#include "worker/engine/eval/exports.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "common/error.h"
#include "common/npy.h"
#include "worker/engine/eval/image_size.h"
#include "worker/engine/eval/quantize.h"

namespace endorecon::eval {
namespace {

void WriteImage(const std::filesystem::path& path, const cv::Mat& image) {
  bool written = false;
  try {
    written = cv::imwrite(path.string(), image);
  } catch (const cv::Exception& e) {
    Fail(ErrorCode::kUnavailable, "cannot write image " + path.string() + ": " + e.what());
  }
  if (!written) Fail(ErrorCode::kUnavailable, "cannot write image " + path.string());
}

}  // namespace

std::string FrameFileName(int index, std::string_view extension) {
  if (index < 0) FailInvalid("frame file name: negative frame index " + std::to_string(index));
  char digits[16];
  std::snprintf(digits, sizeof digits, "%06d", index);
  return std::string(digits) + std::string(extension);
}

void WritePng8(const std::filesystem::path& path, std::span<const float> rgb, int width, int height) {
  CheckImageSize(rgb.size(), width, height, 3, "PNG " + path.string());
  cv::Mat bgr(height, width, CV_8UC3);
  for (int v = 0; v < height; ++v) {
    auto* row = bgr.ptr<std::uint8_t>(v);
    const float* in = rgb.data() + static_cast<std::size_t>(v) * width * 3;
    for (int u = 0; u < width; ++u) {
      for (int c = 0; c < 3; ++c) row[3 * u + c] = ToByte(in[3 * u + 2 - c]);  // OpenCV wants BGR
    }
  }
  WriteImage(path, bgr);
}

double DepthPngScale(double far) {
  if (!std::isfinite(far) || far <= 0)
    FailInvalid("depth PNG scale: far " + std::to_string(far) + " is not > 0");
  return 65535.0 / far;
}

void WriteDepthPng16(const std::filesystem::path& path, std::span<const float> depth, int width, int height,
                     double scale) {
  CheckImageSize(depth.size(), width, height, 1, "depth PNG " + path.string());
  cv::Mat image(height, width, CV_16UC1);
  auto* out = image.ptr<std::uint16_t>(0);
  for (std::size_t p = 0; p < depth.size(); ++p) {
    const double value = static_cast<double>(depth[p]) * scale;
    out[p] = std::isfinite(value) && value > 0
                 ? static_cast<std::uint16_t>(std::lround(std::min(value, 65535.0)))
                 : 0;
  }
  WriteImage(path, image);
}

void WriteDepthNpy(const std::filesystem::path& path, std::span<const float> depth, int width, int height) {
  CheckImageSize(depth.size(), width, height, 1, "depth .npy " + path.string());
  WriteNpyFloat32(path, depth.data(), {static_cast<std::size_t>(height), static_cast<std::size_t>(width)});
}

void WritePly(const std::filesystem::path& path, const PointCloud& cloud) {
  static_assert(std::endian::native == std::endian::little, "PLY vertices are written as stored in memory");
  if (cloud.rgb.size() != cloud.xyz.size() || cloud.xyz.size() % 3 != 0) {
    FailInvalid("PLY " + path.string() + ": " + std::to_string(cloud.xyz.size()) + " coordinates and " +
                std::to_string(cloud.rgb.size()) + " colour values (expected 3 each per point)");
  }
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out << "ply\nformat binary_little_endian 1.0\ncomment endorecon tissue surface, clip units\n"
      << "element vertex " << cloud.size() << "\n"
      << "property float x\nproperty float y\nproperty float z\n"
      << "property uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n";
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    out.write(reinterpret_cast<const char*>(&cloud.xyz[3 * i]), 3 * sizeof(float));
    out.write(reinterpret_cast<const char*>(&cloud.rgb[3 * i]), 3);
  }
  out.close();
  if (!out) Fail(ErrorCode::kUnavailable, "cannot write PLY " + path.string());
}

void WriteHeatmapPng(const std::filesystem::path& path, std::span<const float> values, int width, int height,
                     double vmin, double vmax) {
  CheckImageSize(values.size(), width, height, 1, "heat map " + path.string());
  if (!(vmax > vmin)) {
    FailInvalid("heat map " + path.string() + ": range [" + std::to_string(vmin) + ", " +
                std::to_string(vmax) + "] is empty");
  }
  cv::Mat level(height, width, CV_8UC1);
  auto* out = level.ptr<std::uint8_t>(0);
  for (std::size_t p = 0; p < values.size(); ++p) {
    out[p] = ToByte(static_cast<float>((values[p] - vmin) / (vmax - vmin)));
  }
  cv::Mat colour;
  cv::applyColorMap(level, colour, cv::COLORMAP_INFERNO);
  auto* pixels = colour.ptr<cv::Vec3b>(0);
  for (std::size_t p = 0; p < values.size(); ++p) {
    if (!std::isfinite(values[p])) pixels[p] = cv::Vec3b(128, 128, 128);
  }
  WriteImage(path, colour);
}

double HeatmapUpperBound(std::span<const std::vector<float>> frames, double quantile) {
  std::size_t values = 0;
  for (const auto& frame : frames) values += frame.size();
  HeatmapScale scale(values, std::max<std::size_t>(values, 1));
  for (const auto& frame : frames) scale.Add(frame);
  return scale.UpperBound(quantile);
}

void ClearDepthWithoutSurface(std::span<float> depth, std::span<const float> opacity) {
  if (depth.size() != opacity.size())
    FailInvalid("depth of " + std::to_string(depth.size()) + " pixels and opacity of " +
                std::to_string(opacity.size()));
  for (std::size_t i = 0; i < depth.size(); ++i) {
    if (!(opacity[i] >= kSurfaceOpacity)) depth[i] = 0.0f;
  }
}

HeatmapScale::HeatmapScale(std::size_t values_in_all, std::size_t most_kept)
    : stride_(
          std::max<std::size_t>(1, (values_in_all + most_kept - 1) / std::max<std::size_t>(most_kept, 1))) {
  kept_.reserve(std::min(values_in_all, most_kept));
}

void HeatmapScale::Add(std::span<const float> frame, std::span<const std::uint8_t> left_out) {
  if (!left_out.empty() && left_out.size() != frame.size())
    FailInvalid("heat map scale: a mask of " + std::to_string(left_out.size()) + " pixels for a frame of " +
                std::to_string(frame.size()));
  std::size_t i = next_;
  for (; i < frame.size(); i += stride_) {
    if (std::isfinite(frame[i]) && (left_out.empty() || left_out[i] == 0)) kept_.push_back(frame[i]);
  }
  next_ = i - frame.size();  // the stride runs on across frames
}

double HeatmapScale::UpperBound(double quantile) const {
  if (!(quantile > 0 && quantile <= 1))
    FailInvalid("heat map quantile " + std::to_string(quantile) + " not in (0, 1]");
  if (kept_.empty()) return 1.0;
  std::vector<float> all(kept_);
  const std::size_t k =
      std::min(all.size() - 1, static_cast<std::size_t>(std::ceil(quantile * all.size())) - 1);
  std::nth_element(all.begin(), all.begin() + static_cast<std::ptrdiff_t>(k), all.end());
  return all[k] > 0 ? all[k] : 1.0;
}

}  // namespace endorecon::eval
