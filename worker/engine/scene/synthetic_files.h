// Writing the files of synthetic clips and recordings: PNG frames from linear colours, text files.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <filesystem>
#include <opencv2/core.hpp>
#include <string>

namespace endorecon::scene {

// Linear colour in [0, 1] (clamped) as an 8-bit value, rounded. Inline: the in-memory frames
// (synthetic_frames.cc) use it without linking the file writers below.
inline std::uint8_t ToByte(float value) {
  return static_cast<std::uint8_t>(std::clamp(value, 0.f, 1.f) * 255.f + 0.5f);
}
// Sets pixel (u, v) of an 8-bit BGR image from an RGB colour in [0, 1].
void PutRgb(cv::Mat& bgr, int u, int v, const std::array<float, 3>& rgb);

// Throw Error(kUnavailable) naming the file when it cannot be written.
void WritePng(const std::filesystem::path& path, const cv::Mat& image);
// A w x h image of `channels` 1, 3 (RGB) or 4 (RGBA) bytes a pixel, row-major, as a PNG (whose
// colour OpenCV writes from BGR(A): the channels are reordered, not the bytes changed).
void WriteRgbPng(const std::filesystem::path& path, const std::uint8_t* pixels, int w, int h, int channels);
void WriteText(const std::filesystem::path& path, const std::string& text);

// Makes `out` ready for a synthetic clip: an empty or missing folder is fine; one that holds an
// earlier synthetic clip (synth.json) loses what synth writes; any other non-empty folder is refused
// (Error kInvalidArgument naming it).
void ClearSyntheticFolder(const std::filesystem::path& out);

// "000042": frame file names, six digits.
std::string FrameName(int index);

}  // namespace endorecon::scene
