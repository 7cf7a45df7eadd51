#include "worker/engine/render/adaptive_sampler.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "worker/engine/base/counter_rng.h"
#include "worker/engine/render/stratified_sampler.h"

namespace endorecon::render {
namespace {

constexpr double kNear = 2, kFar = 6;

// 16 coarse samples at bin centres of [2, 6]: cell k is [2 + k/4, 2 + (k+1)/4].
std::vector<double> CoarseSamples() {
  std::vector<double> s(16), delta(16);
  StratifiedSamples(
      kNear, kFar, 16, [](unsigned) { return 0.5; }, s.data(), delta.data());
  return s;
}

void ExpectTilesTheRange(const std::vector<double>& s, const std::vector<double>& delta) {
  double edge = kNear;
  for (std::size_t j = 0; j < s.size(); ++j) {
    ASSERT_GE(delta[j], 0.0);
    EXPECT_GE(s[j], edge - 1e-12) << j;
    EXPECT_LE(s[j], edge + delta[j] + 1e-12) << j;
    edge += delta[j];
  }
  EXPECT_NEAR(edge, kFar, 1e-12);
}

TEST(AdaptiveSampler, NoScoreGivesStratifiedSamples) {
  const std::vector<double> coarse = CoarseSamples();
  const std::vector<double> score(16, 0.0);
  std::vector<double> s(32), delta(32), expected_s(32), expected_delta(32);
  auto half = [](unsigned) { return 0.5; };
  AdaptiveSamples(coarse.data(), score.data(), 16, kNear, kFar, 0.2, 32, half, s.data(), delta.data());
  StratifiedSamples(kNear, kFar, 32, half, expected_s.data(), expected_delta.data());
  for (int j = 0; j < 32; ++j) {
    EXPECT_NEAR(s[j], expected_s[j], 1e-12);
    EXPECT_NEAR(delta[j], expected_delta[j], 1e-12);
  }
}

TEST(AdaptiveSampler, SamplesFollowTheScoreAboveAFloor) {
  // All the score on cell 5 ([3.25, 3.5]); floor 0.25: that cell holds 0.75 + 0.25 / 16 of the mass,
  // every other cell 0.25 / 16 = 1/64. Stratified quantiles put n * mass samples in a cell, +-1.
  const std::vector<double> coarse = CoarseSamples();
  std::vector<double> score(16, 0.0);
  score[5] = 1.7;
  const int n = 128;
  std::vector<double> s(n), delta(n);
  AdaptiveSamples(coarse.data(), score.data(), 16, kNear, kFar, 0.25, n, base::CounterRng<double>(1, 1),
                  s.data(), delta.data());
  ExpectTilesTheRange(s, delta);
  std::vector<int> per_cell(16, 0);
  for (double x : s) per_cell[std::min(15, static_cast<int>((x - kNear) * 4))]++;
  EXPECT_NEAR(per_cell[5], n * (0.75 + 0.25 / 16), 1.0);
  for (int k = 0; k < 16; ++k) {
    if (k != 5) {
      EXPECT_NEAR(per_cell[k], n / 64.0, 1.0) << k;  // the floor: 2 each, never 0
    }
  }
}

TEST(AdaptiveSampler, IntervalsFollowTheDensity) {
  // Each interval holds 1/n of the mass, so one lying inside a single cell k has length
  // 1 / (n p_k), with the density per unit length p_k = floor / L + (1 - floor) S_k / sum(S len).
  const std::vector<double> coarse = CoarseSamples();
  std::vector<double> score(16, 0.0);
  score[3] = 1.0;
  score[12] = 3.0;
  const int n = 64;
  const double floor = 0.5;
  std::vector<double> s(n), delta(n);
  AdaptiveSamples(coarse.data(), score.data(), 16, kNear, kFar, floor, n, base::CounterRng<double>(2, 5),
                  s.data(), delta.data());
  ExpectTilesTheRange(s, delta);
  auto density = [&](int k) { return floor / (kFar - kNear) + (1 - floor) * score[k] / (4.0 * 0.25); };
  int checked = 0;
  double edge = kNear;
  for (int j = 0; j < n; ++j) {
    const int k = std::min(15, static_cast<int>((s[j] - kNear) * 4));
    const double cell_lo = kNear + k * 0.25, cell_hi = cell_lo + 0.25;
    if (edge >= cell_lo - 1e-12 && edge + delta[j] <= cell_hi + 1e-12) {
      EXPECT_NEAR(delta[j], 1.0 / (n * density(k)), 1e-9) << j;
      ++checked;
    }
    edge += delta[j];
  }
  EXPECT_GT(checked, n / 2);
}

TEST(AdaptiveSampler, BadScoresCountAsZero) {
  const std::vector<double> coarse = CoarseSamples();
  std::vector<double> score(16, 0.0);
  score[2] = std::nan("");
  score[7] = -5;
  score[9] = HUGE_VAL;
  std::vector<double> s(32), delta(32);
  AdaptiveSamples(coarse.data(), score.data(), 16, kNear, kFar, 0.1, 32, base::CounterRng<double>(7, 7),
                  s.data(), delta.data());
  for (int j = 0; j < 32; ++j) {
    ASSERT_TRUE(std::isfinite(s[j]));
    EXPECT_NEAR(delta[j], 4.0 / 32, 1e-12);  // uniform: no valid score anywhere
  }
}

TEST(AdaptiveSampler, OneOrNoCoarseSample) {
  const double coarse = 3.0, score = 1.0;
  std::vector<double> s(8), delta(8);
  AdaptiveSamples(&coarse, &score, 1, kNear, kFar, 0.3, 8, base::CounterRng<double>(1, 2), s.data(),
                  delta.data());
  ExpectTilesTheRange(s, delta);
  AdaptiveSamples(static_cast<const double*>(nullptr), static_cast<const double*>(nullptr), 0, kNear, kFar,
                  0.3, 8, base::CounterRng<double>(1, 2), s.data(), delta.data());
  ExpectTilesTheRange(s, delta);
  for (double d : delta) EXPECT_NEAR(d, 0.5, 1e-12);
}

}  // namespace
}  // namespace endorecon::render
