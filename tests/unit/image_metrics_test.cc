#include "worker/engine/eval/image_metrics.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <vector>

#include "worker/engine/eval/psnr.h"

namespace endorecon::eval {
namespace {

constexpr int kW = 24, kH = 16;

TEST(ImageMetrics, TissueNumbersIgnoreTheTool) {
  std::vector<std::uint8_t> reference(kW * kH * 3);
  for (std::size_t i = 0; i < reference.size(); ++i) reference[i] = static_cast<std::uint8_t>(i * 13);
  std::vector<float> rendered(reference.size());
  for (std::size_t i = 0; i < reference.size(); ++i) rendered[i] = reference[i] / 255.0f;
  std::vector<std::uint8_t> mask(kW * kH, 0);
  for (int p = 0; p < 40; ++p) {
    mask[p] = 1;
    rendered[3 * p] = 1.0f - rendered[3 * p];
  }
  const ImageMetrics m = MeasureImage(rendered, reference, mask, kW, kH);
  EXPECT_EQ(m.psnr_tissue, kPsnrCapDb);
  EXPECT_LT(m.psnr, 40.0);
  EXPECT_NEAR(m.ssim_tissue, 1.0, 1e-6);
  EXPECT_LT(m.ssim, m.ssim_tissue);
  EXPECT_EQ(m.tissue_pixels, kW * kH - 40);

  const ImageMetrics unmasked = MeasureImage(rendered, reference, {}, kW, kH);
  EXPECT_EQ(unmasked.psnr_tissue, unmasked.psnr);
  EXPECT_EQ(unmasked.tissue_pixels, kW * kH);
}

// A 12x9 frame (a 24x18 clip rendered at stride 2) has no SSIM: NaN, not a failed job (found
// 2026-12-05: "SSIM: image 12x9 is smaller than the 11x11 window" failed the job after training).
TEST(ImageMetrics, AFrameSmallerThanTheSsimWindowHasPsnrAndNoSsim) {
  constexpr int w = 12, h = 9;
  std::vector<std::uint8_t> reference(w * h * 3, 100);
  std::vector<float> rendered(reference.size(), 100 / 255.0f);
  rendered[0] = 0;
  const ImageMetrics m = MeasureImage(rendered, reference, std::vector<std::uint8_t>(w * h, 0), w, h);
  EXPECT_TRUE(std::isfinite(m.psnr));
  EXPECT_LT(m.psnr, kPsnrCapDb);
  EXPECT_TRUE(std::isnan(m.ssim));
  EXPECT_TRUE(std::isnan(m.ssim_tissue));
  EXPECT_NE(ToJson(m).dump().find("\"ssim\":null"), std::string::npos) << ToJson(m).dump();
}

TEST(ImageMetrics, FramesSerialiseWithSummaryAndNulls) {
  const std::vector<ImageMetrics> frames = {{30, 0.9, 32, 0.92, 100},
                                            {34, 0.8, std::nan(""), std::nan(""), 0}};
  const nlohmann::json j = nlohmann::json::parse(ToJson(frames).dump());
  EXPECT_DOUBLE_EQ(j["psnr"]["mean"].get<double>(), 32.0);
  EXPECT_DOUBLE_EQ(j["psnr_tissue"]["mean"].get<double>(), 32.0);
  EXPECT_EQ(j["psnr_tissue"]["count"].get<int>(), 1);
  EXPECT_TRUE(j["per_frame"][1]["ssim_tissue"].is_null());
}

}  // namespace
}  // namespace endorecon::eval
