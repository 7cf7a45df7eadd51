#include "worker/engine/scene/synthetic_files.h"

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "common/error.h"

namespace endorecon::scene {

void PutRgb(cv::Mat& bgr, int u, int v, const std::array<float, 3>& rgb) {
  bgr.at<cv::Vec3b>(v, u) = {ToByte(rgb[2]), ToByte(rgb[1]), ToByte(rgb[0])};
}

void WritePng(const std::filesystem::path& path, const cv::Mat& image) {
  if (!cv::imwrite(path.string(), image)) Fail(ErrorCode::kUnavailable, "cannot write " + path.string());
}

void WriteRgbPng(const std::filesystem::path& path, const std::uint8_t* pixels, int w, int h, int channels) {
  const cv::Mat image(h, w, CV_MAKETYPE(CV_8U, channels), const_cast<std::uint8_t*>(pixels));
  if (channels == 1) return WritePng(path, image);
  cv::Mat bgr;
  cv::cvtColor(image, bgr, channels == 3 ? cv::COLOR_RGB2BGR : cv::COLOR_RGBA2BGRA);
  WritePng(path, bgr);
}

void WriteText(const std::filesystem::path& path, const std::string& text) {
  std::ofstream file(path, std::ios::trunc);
  file << text;
  file.close();
  if (!file) Fail(ErrorCode::kUnavailable, "cannot write " + path.string());
}

void ClearSyntheticFolder(const std::filesystem::path& out) {
  namespace fs = std::filesystem;
  if (!fs::exists(out) || fs::is_empty(out)) return;
  if (!fs::exists(out / "synth.json")) {
    FailInvalid(out.string() + ": exists and is not empty (and holds no synthetic clip to replace)");
  }
  for (const char* entry : {"images", "depth", "masks", "images_right", "gt", "recording", "poses_bounds.npy",
                            "stereo.json", "transforms.json"}) {
    fs::remove_all(out / entry);
  }
}

std::string FrameName(int index) {
  char name[32];
  std::snprintf(name, sizeof(name), "%06d", index);
  return name;
}

}  // namespace endorecon::scene
