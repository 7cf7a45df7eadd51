// Builds small clips on disk for the loader tests: PNG frames and EndoNeRF pose files.
#pragma once

#include <gtest/gtest.h>

#include <cstdint>
#include <filesystem>
#include <functional>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <string>
#include <vector>

#include "common/error.h"
#include "common/npy.h"

namespace endorecon::testing {

// A w x h image of `type` whose pixel (x, y) is fill(x, y) on every channel.
inline cv::Mat Pattern(int w, int h, int type, const std::function<double(int, int)>& fill) {
  cv::Mat image(h, w, type);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const double v = fill(x, y);
      switch (image.channels()) {
        case 1:
          if (image.depth() == CV_8U)
            image.at<std::uint8_t>(y, x) = static_cast<std::uint8_t>(v);
          else
            image.at<std::uint16_t>(y, x) = static_cast<std::uint16_t>(v);
          break;
        default:
          image.at<cv::Vec3b>(y, x) =
              cv::Vec3b(static_cast<std::uint8_t>(v), static_cast<std::uint8_t>(v / 2), 7);
      }
    }
  }
  return image;
}

inline void WriteImage(const std::filesystem::path& path, const cv::Mat& image) {
  std::filesystem::create_directories(path.parent_path());
  ASSERT_TRUE(cv::imwrite(path.string(), image)) << path;
}

// One EndoNeRF pose row: LLFF rotation `r` (row-major 3x3), translation t, H, W, f, near, far.
struct PoseRow {
  double r[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  double t[3] = {0, 0, 0};
  double h = 6, w = 8, f = 10, near = 1, far = 20;
};

inline void WritePoses(const std::filesystem::path& path, const std::vector<PoseRow>& rows) {
  std::vector<double> data;
  for (const PoseRow& p : rows) {
    const double row[17] = {p.r[0], p.r[1], p.r[2], p.t[0], p.h,    p.r[3], p.r[4], p.r[5], p.t[1],
                            p.w,    p.r[6], p.r[7], p.r[8], p.t[2], p.f,    p.near, p.far};
    data.insert(data.end(), row, row + 17);
  }
  WriteNpyFloat64(path, data.data(), {rows.size(), 17});
}

// The error a call throws (fails the test if none), checking its code.
template <typename F>
std::string ErrorFrom(F&& call, ErrorCode expected = ErrorCode::kInvalidArgument) {
  try {
    call();
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), expected) << e.what();
    return e.what();
  }
  ADD_FAILURE() << "no error thrown";
  return "";
}

}  // namespace endorecon::testing
