#include "worker/engine/eval/calibration.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <random>
#include <vector>

#include "common/error.h"

namespace endorecon::eval {
namespace {

std::vector<float> Errors(int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> value(0.0f, 1.0f);
  std::vector<float> e(n);
  for (auto& v : e) v = value(rng);
  return e;
}

TEST(Calibration, PerfectRankingHasNoArea) {
  const std::vector<float> error = Errors(500, 1);
  std::vector<float> uncertainty(error.size());
  for (std::size_t i = 0; i < error.size(); ++i) uncertainty[i] = 3.0f * error[i] * error[i];  // monotone
  const Calibration c = MeasureCalibration(uncertainty, error, {});
  EXPECT_NEAR(c.ause, 0.0, 1e-12);
  EXPECT_NEAR(c.spearman, 1.0, 1e-12);
  EXPECT_GT(c.pearson, 0.9);
  EXPECT_LT(c.pearson, 1.0);
  ASSERT_EQ(c.curves.fractions.size(), static_cast<std::size_t>(kSparsificationSteps));
  EXPECT_DOUBLE_EQ(c.curves.fractions[1], 0.02);
  EXPECT_NEAR(c.curves.oracle[0], 1.0, 1e-12);
  EXPECT_LT(c.curves.oracle.back(), 0.1);
}

TEST(Calibration, ReversedRankingIsTheWorst) {
  const std::vector<float> error = Errors(500, 2);
  std::vector<float> reversed(error.size());
  for (std::size_t i = 0; i < error.size(); ++i) reversed[i] = -error[i];
  const Calibration worst = MeasureCalibration(reversed, error, {});
  EXPECT_NEAR(worst.spearman, -1.0, 1e-12);
  EXPECT_NEAR(worst.pearson, -1.0, 1e-12);
  std::mt19937 rng(3);
  for (int trial = 0; trial < 20; ++trial) {
    std::vector<float> shuffled = error;
    std::shuffle(shuffled.begin(), shuffled.end(), rng);
    const Calibration random = MeasureCalibration(shuffled, error, {});
    EXPECT_LT(random.ause, worst.ause);
    EXPECT_GT(random.ause, 0.0);
  }
}

TEST(Calibration, SmallCaseByHand) {
  // Errors 1..4 (mean 2.5); uncertainty orders the pixels (e=2, e=3, e=4, e=1), steps of 1/4.
  // Mean error left, by uncertainty: 2.5, 8/3, 2.5, 1 -> /2.5: 1, 16/15, 1, 0.4.
  // Oracle: 2.5, 2, 1.5, 1 -> 1, 0.8, 0.6, 0.4. Gap 0, 4/15, 0.4, 0; trapezoid area 1/6.
  const std::vector<float> error = {1, 2, 3, 4};
  const std::vector<float> uncertainty = {0.1f, 0.4f, 0.3f, 0.2f};
  const Calibration c = MeasureCalibration(uncertainty, error, {}, 4);
  const std::vector<double> by_uncertainty = {1, 16.0 / 15, 1, 0.4}, oracle = {1, 0.8, 0.6, 0.4};
  for (int i = 0; i < 4; ++i) {
    EXPECT_DOUBLE_EQ(c.curves.fractions[i], i / 4.0);
    EXPECT_NEAR(c.curves.by_uncertainty[i], by_uncertainty[i], 1e-12) << i;
    EXPECT_NEAR(c.curves.oracle[i], oracle[i], 1e-12) << i;
  }
  EXPECT_NEAR(c.ause, 1.0 / 6, 1e-7);
  EXPECT_NEAR(c.spearman, 0.2, 1e-12);  // 1 - 6 * 8 / (4 * 15)
  EXPECT_NEAR(c.pearson, 0.2, 1e-6);
}

TEST(Calibration, TiesUseAverageRanksAndExpectedRemoval) {
  // Uncertainty ties: {4, 2} share the top, {3, 1} the bottom. Removing 1 pixel takes the top
  // group's mean 3 in expectation: left (10 - 3) / 3; 2: (10 - 6) / 2; 3: (10 - 8) / 1.
  const std::vector<float> error = {4, 2, 3, 1};
  const std::vector<float> uncertainty = {1, 1, 0, 0};
  const Calibration c = MeasureCalibration(uncertainty, error, {}, 4);
  const std::vector<double> expected = {1, 7.0 / 3 / 2.5, 0.8, 0.8};
  for (int i = 0; i < 4; ++i) EXPECT_NEAR(c.curves.by_uncertainty[i], expected[i], 1e-12) << i;
  // Ranks (3.5, 3.5, 1.5, 1.5) against (4, 2, 3, 1): covariance 2, variances 4 and 5.
  EXPECT_NEAR(c.spearman, 2 / std::sqrt(20.0), 1e-12);
}

TEST(Calibration, ConstantUncertaintyIsTheRandomCurve) {
  const std::vector<float> error = Errors(300, 4);
  const std::vector<float> uncertainty(error.size(), 0.5f);
  const Calibration c = MeasureCalibration(uncertainty, error, {});
  EXPECT_EQ(c.spearman, 0.0);
  EXPECT_EQ(c.pearson, 0.0);
  for (double v : c.curves.by_uncertainty) EXPECT_NEAR(v, 1.0, 1e-9);
  double area = 0;  // trapezoid of (1 - oracle)
  for (std::size_t i = 1; i < c.curves.oracle.size(); ++i) {
    area += 0.02 * ((1 - c.curves.oracle[i]) + (1 - c.curves.oracle[i - 1])) / 2;
  }
  EXPECT_NEAR(c.ause, area, 1e-9);
  EXPECT_GT(c.ause, 0.2);
}

TEST(Calibration, ZeroErrorEverywhereIsPerfect) {
  const std::vector<float> error(64, 0.0f);
  const Calibration c = MeasureCalibration(Errors(64, 5), error, {});
  EXPECT_EQ(c.ause, 0.0);
  EXPECT_EQ(c.spearman, 0.0);
  for (double v : c.curves.oracle) EXPECT_EQ(v, 0.0);
}

// Errors below what the measure can tell rank only noise: NaN, as a frame with nothing to rank.
TEST(Calibration, ErrorsBelowTheResolutionAreNotRanked) {
  std::vector<float> error(64), uncertainty(64);
  for (int i = 0; i < 64; ++i) {
    error[i] = 1e-5f * static_cast<float>(i);  // float noise of a perfect render: well under 0.5/255
    uncertainty[i] = static_cast<float>(64 - i);
  }
  const Calibration unresolved =
      MeasureCalibration(uncertainty, error, {}, kSparsificationSteps, kEightBitErrorResolution);
  EXPECT_TRUE(std::isnan(unresolved.spearman));
  EXPECT_TRUE(std::isnan(unresolved.ause));
  EXPECT_TRUE(unresolved.curves.fractions.empty());
  EXPECT_EQ(unresolved.pixels, 64);
  const Calibration ranked = MeasureCalibration(uncertainty, error, {});
  EXPECT_NEAR(ranked.spearman, -1, 1e-12) << "without a resolution the same errors are ranked";
  for (float& e : error) e += 0.01f;  // errors of a couple of 8-bit steps are ranked
  EXPECT_NEAR(
      MeasureCalibration(uncertainty, error, {}, kSparsificationSteps, kEightBitErrorResolution).spearman, -1,
      1e-12);
}

TEST(Calibration, ToolPixelsAreLeftOut) {
  std::vector<float> error = {1, 2, 3, 4, 100, 100};
  std::vector<float> uncertainty = {1, 2, 3, 4, -50, -60};  // tool pixels would break the ranking
  const std::vector<std::uint8_t> mask = {0, 0, 0, 0, 1, 1};
  const Calibration c = MeasureCalibration(uncertainty, error, mask, 4);
  EXPECT_EQ(c.pixels, 4);
  EXPECT_NEAR(c.spearman, 1.0, 1e-12);
  EXPECT_NEAR(c.ause, 0.0, 1e-12);
}

TEST(Calibration, UndefinedFramesAreNaNNotNumbers) {
  const std::vector<float> error = {1, 2, 3};
  const Calibration all_tool = MeasureCalibration(error, error, std::vector<std::uint8_t>{1, 1, 1});
  EXPECT_TRUE(std::isnan(all_tool.ause));
  EXPECT_TRUE(all_tool.curves.fractions.empty());
  const std::vector<float> uncertainty = {1, std::nanf(""), 3};
  EXPECT_TRUE(std::isnan(MeasureCalibration(uncertainty, error, {}).spearman));
}

TEST(Calibration, BadInputThrows) {
  const std::vector<float> error = {1, 2, 3};
  EXPECT_THROW(MeasureCalibration(std::vector<float>{1, 2}, error, {}), Error);
  EXPECT_THROW(MeasureCalibration(error, error, {}, 0), Error);
}

TEST(Calibration, SummaryAveragesFramesAndCurves) {
  const std::vector<float> error = {1, 2, 3, 4};
  const std::vector<Calibration> frames = {
      MeasureCalibration(std::vector<float>{0.1f, 0.4f, 0.3f, 0.2f}, error, {}, 4),
      MeasureCalibration(error, error, {}, 4),
      MeasureCalibration(error, error, std::vector<std::uint8_t>{1, 1, 1, 1}, 4)};
  const CalibrationSummary s = SummariseCalibration(frames);
  EXPECT_EQ(s.spearman.count, 2);
  EXPECT_NEAR(s.spearman.mean, 0.6, 1e-12);
  EXPECT_NEAR(s.spearman.std, 0.4, 1e-12);
  EXPECT_NEAR(s.ause.mean, 1.0 / 12, 1e-7);
  ASSERT_EQ(s.mean_curves.by_uncertainty.size(), 4u);
  EXPECT_NEAR(s.mean_curves.by_uncertainty[1], (16.0 / 15 + 0.8) / 2, 1e-12);

  const nlohmann::json j = nlohmann::json::parse(ToJson(frames).dump());
  EXPECT_EQ(j["curves"]["oracle"].size(), 4u);
  EXPECT_EQ(j["per_frame"].size(), 3u);
  EXPECT_FALSE(j["per_frame"][0].contains("curves"));
  EXPECT_TRUE(j["per_frame"][2]["ause"].is_null());
  EXPECT_EQ(ToJson(frames[0])["curves"]["by_uncertainty"].size(), 4u);
}

TEST(Calibration, SummaryRejectsMixedSteps) {
  const std::vector<float> error = {1, 2, 3, 4};
  const std::vector<Calibration> frames = {MeasureCalibration(error, error, {}, 4),
                                           MeasureCalibration(error, error, {}, 2)};
  EXPECT_THROW(SummariseCalibration(frames), Error);
}

}  // namespace
}  // namespace endorecon::eval
