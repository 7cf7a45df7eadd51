#include "worker/engine/eval/ssim.h"

#include <gtest/gtest.h>

#include <algorithm>
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

// SSIM by its definition, window by window: an 11x11 Gaussian (sigma 1.5) over every window wholly
// inside the frame, tool pixels set to 0 first and left out of the mean.
double SsimByDefinition(const std::vector<float>& rendered, const std::vector<std::uint8_t>& reference,
                        const std::vector<std::uint8_t>& mask, int w, int h) {
  double g[11], total = 0;
  for (int i = 0; i < 11; ++i) total += g[i] = std::exp(-(i - 5) * (i - 5) / (2 * 1.5 * 1.5));
  for (double& v : g) v /= total;
  const auto value = [&](const auto& image, int v, int u, int c, double scale) {
    return !mask.empty() && mask[v * w + u] ? 0.0 : std::clamp(image[3 * (v * w + u) + c] * scale, 0.0, 1.0);
  };
  double sum = 0;
  long kept = 0;
  for (int v = 5; v < h - 5; ++v) {
    for (int u = 5; u < w - 5; ++u) {
      if (!mask.empty() && mask[v * w + u]) continue;
      double pixel = 0;
      for (int c = 0; c < 3; ++c) {
        double mx = 0, my = 0, xx = 0, yy = 0, xy = 0;
        for (int i = -5; i <= 5; ++i) {
          for (int j = -5; j <= 5; ++j) {
            const double k = g[i + 5] * g[j + 5];
            const double x = value(rendered, v + i, u + j, c, 1.0);
            const double y = value(reference, v + i, u + j, c, 1 / 255.0);
            mx += k * x, my += k * y, xx += k * x * x, yy += k * y * y, xy += k * x * y;
          }
        }
        const double c1 = 1e-4, c2 = 9e-4;
        pixel += (2 * mx * my + c1) * (2 * (xy - mx * my) + c2) /
                 ((mx * mx + my * my + c1) * (xx - mx * mx + yy - my * my + c2));
      }
      sum += pixel / 3;
      ++kept;
    }
  }
  return sum / kept;
}

TEST(Ssim, AFrameOfManyStripsScoresAsTheDefinition) {
  // Taller than several of the strips Ssim scores at a time, the last one short.
  constexpr int w = 37, h = 83;
  std::mt19937 rng(5);
  std::uniform_int_distribution<int> value(0, 255);
  std::normal_distribution<float> noise(0.0f, 0.08f);
  std::vector<std::uint8_t> reference(w * h * 3), mask(w * h, 0);
  std::vector<float> rendered(reference.size());
  for (std::size_t i = 0; i < reference.size(); ++i) {
    reference[i] = static_cast<std::uint8_t>(value(rng));
    rendered[i] = reference[i] / 255.0f + noise(rng);  // some values outside [0, 1], to be clamped
  }
  for (int v = 30; v < 50; ++v) {
    for (int u = 3; u < 20; ++u) mask[v * w + u] = 1;
  }
  EXPECT_NEAR(Ssim(rendered, reference, {}, w, h), SsimByDefinition(rendered, reference, {}, w, h), 1e-12);
  EXPECT_NEAR(Ssim(rendered, reference, mask, w, h), SsimByDefinition(rendered, reference, mask, w, h),
              1e-12);
}

TEST(Ssim, FrameSmallerThanWindowThrows) {
  const std::vector<std::uint8_t> reference(10 * 10 * 3, 7);
  EXPECT_THROW(Ssim(std::vector<float>(10 * 10 * 3), reference, {}, 10, 10), Error);
}

}  // namespace
}  // namespace endorecon::eval
