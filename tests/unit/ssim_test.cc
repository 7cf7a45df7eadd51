#include "worker/engine/eval/ssim.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include "common/error.h"

namespace endorecon::eval {
namespace {

constexpr int kW = 40, kH = 32;

std::vector<std::uint8_t> Texture(unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> value(0, 255);
  std::vector<std::uint8_t> image(kW * kH * 3);
  for (auto& v : image) v = static_cast<std::uint8_t>(value(rng));
  return image;
}

std::vector<float> AsFloat(const std::vector<std::uint8_t>& image) {
  std::vector<float> out(image.size());
  for (std::size_t i = 0; i < image.size(); ++i) out[i] = image[i] / 255.0f;
  return out;
}

TEST(Ssim, IdenticalImagesGiveOne) {
  const auto reference = Texture(1);
  EXPECT_NEAR(Ssim(AsFloat(reference), reference, {}, kW, kH), 1.0, 1e-6);
}

TEST(Ssim, ConstantImagesGiveLuminanceTerm) {
  // Flat windows: variances and covariance vanish, SSIM = (2ab + C1) / (a^2 + b^2 + C1).
  const std::vector<std::uint8_t> reference(kW * kH * 3, 100);
  const double a = 0.5, b = 100 / 255.0, c1 = 1e-4;
  EXPECT_NEAR(Ssim(std::vector<float>(kW * kH * 3, 0.5f), reference, {}, kW, kH),
              (2 * a * b + c1) / (a * a + b * b + c1), 1e-9);
}

TEST(Ssim, NegativeImageScoresLow) {
  const auto reference = Texture(2);
  std::vector<float> negative(reference.size());
  for (std::size_t i = 0; i < reference.size(); ++i) negative[i] = 1.0f - reference[i] / 255.0f;
  const double ssim = Ssim(negative, reference, {}, kW, kH);
  EXPECT_LT(ssim, 0.5);
  EXPECT_GT(ssim, -1.0);
}

TEST(Ssim, ToolPixelsAreLeftOut) {
  const auto reference = Texture(3);
  std::vector<float> rendered = AsFloat(reference);
  std::vector<std::uint8_t> mask(kW * kH, 0);
  for (int v = 10; v < 20; ++v) {
    for (int u = 12; u < 30; ++u) {
      mask[v * kW + u] = 1;
      for (int c = 0; c < 3; ++c) rendered[3 * (v * kW + u) + c] = 0.9f;  // tissue behind the tool
    }
  }
  EXPECT_NEAR(Ssim(rendered, reference, mask, kW, kH), 1.0, 1e-6);
  EXPECT_LT(Ssim(rendered, reference, {}, kW, kH), 0.9);
}

TEST(Ssim, AllToolFrameIsUndefined) {
  const auto reference = Texture(4);
  EXPECT_TRUE(std::isnan(Ssim(AsFloat(reference), reference, std::vector<std::uint8_t>(kW * kH, 1), kW, kH)));
}

TEST(Ssim, FrameSmallerThanWindowThrows) {
  const std::vector<std::uint8_t> reference(10 * 10 * 3, 7);
  EXPECT_THROW(Ssim(std::vector<float>(10 * 10 * 3), reference, {}, 10, 10), Error);
}

}  // namespace
}  // namespace endorecon::eval
