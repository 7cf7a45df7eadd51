#include "worker/engine/eval/psnr.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <vector>

#include "common/error.h"

namespace endorecon::eval {
namespace {

constexpr int kW = 16, kH = 12;

std::vector<float> AsFloat(const std::vector<std::uint8_t>& image, float offset = 0) {
  std::vector<float> out(image.size());
  for (std::size_t i = 0; i < image.size(); ++i) out[i] = image[i] / 255.0f + offset;
  return out;
}

TEST(Psnr, ConstantOffsetGivesClosedForm) {
  const std::vector<std::uint8_t> reference(kW * kH * 3, 100);
  // MSE = 0.05^2 -> PSNR = -10 log10(0.0025) = 26.0206 dB.
  EXPECT_NEAR(Psnr(AsFloat(reference, 0.05f), reference, {}, kW, kH), -10 * std::log10(0.0025), 1e-4);
}

TEST(Psnr, IdenticalImagesAreCapped) {
  std::vector<std::uint8_t> reference(kW * kH * 3);
  for (std::size_t i = 0; i < reference.size(); ++i) reference[i] = static_cast<std::uint8_t>(i * 7);
  EXPECT_EQ(Psnr(AsFloat(reference), reference, {}, kW, kH), kPsnrCapDb);
}

// The training step's PSNR (the curve's and the log's train_psnr) keeps the same cap: it reached
// 120 dB on an all-white clip (found 2026-12-06).
TEST(Psnr, TheStepsPsnrFromItsMseHasTheSameCap) {
  EXPECT_EQ(base::PsnrFromMse(0), kPsnrCapDb);
  EXPECT_EQ(base::PsnrFromMse(1e-12), kPsnrCapDb);
  EXPECT_NEAR(base::PsnrFromMse(0.0025), -10 * std::log10(0.0025), 1e-12);
  EXPECT_TRUE(std::isnan(base::PsnrFromMse(std::nan(""))));
}

TEST(Psnr, RenderedValuesAreClampedToUnitRange) {
  const std::vector<std::uint8_t> reference(kW * kH * 3, 255);
  EXPECT_EQ(Psnr(std::vector<float>(kW * kH * 3, 3.0f), reference, {}, kW, kH), kPsnrCapDb);
}

TEST(Psnr, ToolPixelsAreLeftOut) {
  const std::vector<std::uint8_t> reference(kW * kH * 3, 100);
  std::vector<float> rendered = AsFloat(reference, 0.05f);
  std::vector<std::uint8_t> mask(kW * kH, 0);
  for (int p = 0; p < kW * kH; p += 3) {
    mask[p] = 1;
    for (int c = 0; c < 3; ++c) rendered[3 * p + c] = 1.0f;  // a badly wrong tool pixel
  }
  EXPECT_NEAR(Psnr(rendered, reference, mask, kW, kH), -10 * std::log10(0.0025), 1e-4);
  EXPECT_LT(Psnr(rendered, reference, {}, kW, kH), 20.0);
}

TEST(Psnr, AllToolFrameIsUndefined) {
  const std::vector<std::uint8_t> reference(kW * kH * 3, 100);
  const std::vector<std::uint8_t> mask(kW * kH, 1);
  EXPECT_TRUE(std::isnan(Psnr(AsFloat(reference), reference, mask, kW, kH)));
}

TEST(Psnr, NonFiniteRenderingIsReportedNotHidden) {
  const std::vector<std::uint8_t> reference(kW * kH * 3, 100);
  std::vector<float> rendered = AsFloat(reference);
  rendered[5] = std::nanf("");
  EXPECT_TRUE(std::isnan(Psnr(rendered, reference, {}, kW, kH)));
}

TEST(Psnr, SizeMismatchThrows) {
  const std::vector<std::uint8_t> reference(kW * kH * 3, 100);
  EXPECT_THROW(Psnr(std::vector<float>(kW * kH * 3 - 1), reference, {}, kW, kH), Error);
  EXPECT_THROW(Psnr(AsFloat(reference), reference, std::vector<std::uint8_t>(7), kW, kH), Error);
}

}  // namespace
}  // namespace endorecon::eval
