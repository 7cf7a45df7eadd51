// The model map: the aleatoric score's excess over what the frame's pixels of the same brightness
// show (the camera's noise), plus the epistemic score, each relative to its tissue mean.
#include "worker/engine/eval/model_uncertainty.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <vector>

#include "common/error.h"

namespace endorecon::eval {
namespace {

// 200 pixels in two brightness levels; the aleatoric score follows the brightness (noise: 4x where
// bright), with a few pixels of each level twice their level's score (the model's own error).
struct Frame {
  std::vector<float> rgb, aleatoric, epistemic;
  std::vector<std::uint8_t> mask;
};

Frame TwoLevels() {
  Frame f;
  for (int i = 0; i < 200; ++i) {
    const bool bright = i % 2 == 0;
    const float v = bright ? 0.8f : 0.2f;
    f.rgb.insert(f.rgb.end(), {v, v, v});
    const float noise = bright ? 4.0f : 1.0f;
    f.aleatoric.push_back(noise * (i % 20 < 2 ? 2.0f : 1.0f) * (1.0f + 0.001f * float(i % 7)));
    f.epistemic.push_back(0.0f);
  }
  return f;
}

TEST(ModelUncertaintyTest, TheNoiseOfABrightnessIsTakenOutAndTheExcessRanks) {
  const Frame f = TwoLevels();
  const auto map = ModelUncertainty(f.rgb, f.aleatoric, f.epistemic, {});
  // A dark pixel with excess ranks above a bright pixel without, though its aleatoric score is lower.
  EXPECT_LT(f.aleatoric[1], f.aleatoric[2]);  // pixel 1: dark, excess; pixel 2: bright, none
  EXPECT_GT(map[1], map[2]);
  // Without excess, both levels come out alike: the ratio to their own median, about 1 / mean.
  EXPECT_NEAR(map[2] / map[3], 1.0, 0.01);
  // No epistemic term (all zero): it adds nothing; the excess term has mean 1 over the tissue.
  double mean = 0;
  for (float v : map) mean += v / map.size();
  EXPECT_NEAR(mean, 1.0, 1e-6);
}

TEST(ModelUncertaintyTest, TheEpistemicScoreAddsRelativeToItsMean) {
  Frame f = TwoLevels();
  for (std::size_t i = 0; i < f.epistemic.size(); ++i) f.epistemic[i] = i == 5 ? 1e-3f : 1e-6f;
  const auto map = ModelUncertainty(f.rgb, f.aleatoric, f.epistemic, {});
  const auto plain = ModelUncertainty(f.rgb, f.aleatoric, std::vector<float>(f.aleatoric.size(), 0.0f), {});
  // Pixel 5's epistemic score is about 167 times the mean: the map's largest value, whatever the
  // scores' units (1e-3 against aleatoric scores of 1 to 8).
  EXPECT_EQ(std::max_element(map.begin(), map.end()) - map.begin(), 5);
  EXPECT_GT(map[5] - plain[5], 100.0);
}

TEST(ModelUncertaintyTest, ToolPixelsAreLeftOutOfTheCurveAndTheMeans) {
  Frame f = TwoLevels();
  f.mask.assign(200, 0);
  // Tool pixels: bright, with a huge aleatoric score; they must not move the bright level's median.
  for (int i = 100; i < 200; i += 2) {
    f.mask[i] = 1;
    f.aleatoric[i] = 1000.0f;
  }
  const auto masked = ModelUncertainty(f.rgb, f.aleatoric, f.epistemic, f.mask);
  EXPECT_NEAR(masked[2] / masked[3], 1.0, 0.01);
  EXPECT_THROW(ModelUncertainty(f.rgb, f.aleatoric, f.epistemic, std::vector<std::uint8_t>(3, 0)), Error);
  EXPECT_THROW(ModelUncertainty(std::vector<float>(5), f.aleatoric, f.epistemic, {}), Error);
}

TEST(ModelUncertaintyTest, ANeighbourTermAddsRelativeToItsMeanAtItsWeight) {
  Frame f = TwoLevels();
  f.mask.assign(200, 0);
  f.mask[9] = 1;
  const auto plain = ModelUncertainty(f.rgb, f.aleatoric, f.epistemic, f.mask);
  std::vector<float> evidence(200, 1e-4f);
  evidence[3] = 1e-2f;  // far above the mean, in the evidence's own units
  evidence[9] = 1e3f;   // the tool: out of the mean
  auto map = plain;
  AddNeighbourTerm(map, evidence, 0.7, f.mask);
  double mean = 0;
  for (int i = 0; i < 200; ++i) mean += i == 9 ? 0.0 : evidence[i] / 199.0;
  EXPECT_NEAR(map[0] - plain[0], 0.7 * 1e-4 / mean, 1e-4);
  EXPECT_NEAR(map[3] - plain[3], 0.7 * 1e-2 / mean, 1e-2);
  EXPECT_EQ(std::max_element(map.begin(), map.end()) - map.begin(), 9);  // the tool's value is its own
  // A term that is 0 everywhere adds nothing; sizes that disagree are refused.
  auto unchanged = plain;
  AddNeighbourTerm(unchanged, std::vector<float>(200, 0.0f), 0.7, f.mask);
  EXPECT_EQ(unchanged, plain);
  EXPECT_THROW(AddNeighbourTerm(map, std::vector<float>(3), 0.7, {}), Error);
}

}  // namespace
}  // namespace endorecon::eval
