#include "worker/engine/render/depth_guided_sampler.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "worker/engine/base/counter_rng.h"

namespace endorecon::render {
namespace {

struct Drawn {
  std::vector<double> s, delta;
  int n = 0;
};

Drawn Draw(double near, double far, double prior, const DepthGuidedConfig<double>& config, uint64_t stream) {
  Drawn d;
  d.s.resize(config.gaussian_samples + config.stratified_samples);
  d.delta.resize(d.s.size());
  d.n = DepthGuidedSamples(near, far, prior, config, base::CounterRng<double>(3, stream), d.s.data(),
                           d.delta.data());
  return d;
}

TEST(DepthGuidedSampler, SamplesClusterAroundThePriorSortedInRange) {
  const DepthGuidedConfig<double> config{0.2, 56, 8};
  const double near = 1, far = 9, prior = 4;
  int within_3xi = 0, total = 0;
  double gaussian_sum = 0;
  for (uint64_t ray = 0; ray < 200; ++ray) {
    const Drawn d = Draw(near, far, prior, config, ray);
    ASSERT_EQ(d.n, 64);
    double covered = 0;
    for (int j = 0; j < d.n; ++j) {
      ASSERT_GE(d.s[j], near);
      ASSERT_LE(d.s[j], far);
      if (j > 0) {
        ASSERT_GE(d.s[j], d.s[j - 1]);
      }
      ASSERT_GE(d.delta[j], 0.0);
      covered += d.delta[j];
      within_3xi += std::fabs(d.s[j] - prior) <= 3 * config.xi;
      if (std::fabs(d.s[j] - prior) <= 3 * config.xi) gaussian_sum += d.s[j];
      ++total;
    }
    EXPECT_LE(covered, far - near + 1e-12);
  }
  // 56 of 64 samples are Gaussian (99.7% of them within 3 xi); of the 8 stratified ones about
  // 8 * 1.2 / 8 = 1.2 per ray fall there too.
  EXPECT_GT(within_3xi, total * 56 / 64 * 0.99);
  EXPECT_NEAR(gaussian_sum / within_3xi, prior, 0.01);
}

TEST(DepthGuidedSampler, StratifiedPartStillSeesEmptySpace) {
  const DepthGuidedConfig<double> config{0.1, 24, 8};
  const Drawn d = Draw(0.0, 8.0, 5.0, config, 1);
  int in_front = 0, behind = 0;
  for (double s : d.s) {
    in_front += s < 4.0;
    behind += s > 6.0;
  }
  EXPECT_GE(in_front, 4);  // the stratified bins [0,1) .. [3,4)
  EXPECT_GE(behind, 2);    // [6,7), [7,8)
}

TEST(DepthGuidedSampler, UnknownPriorFallsBackToStratified) {
  const DepthGuidedConfig<double> config{0.1, 12, 4};
  for (double prior : {0.0, -2.0, std::nan("")}) {
    const Drawn d = Draw(2.0, 6.0, prior, config, 4);
    ASSERT_EQ(d.n, 16);
    for (int j = 0; j < 16; ++j) {
      EXPECT_NEAR(d.delta[j], 0.25, 1e-12);
      EXPECT_GE(d.s[j], 2.0 + 0.25 * j);
      EXPECT_LT(d.s[j], 2.0 + 0.25 * (j + 1));
    }
  }
}

TEST(DepthGuidedSampler, PriorOutsideTheRangeClampsOntoItsEnd) {
  const DepthGuidedConfig<double> config{0.01, 8, 0};
  const Drawn d = Draw(1.0, 3.0, 10.0, config, 2);
  for (int j = 0; j < d.n; ++j) {
    EXPECT_EQ(d.s[j], 3.0);
    EXPECT_TRUE(std::isfinite(d.delta[j]));
    EXPECT_GE(d.delta[j], 0.0);
  }
}

// The trainer's sample reallocation regenerates a ray's Gaussian samples with GaussianSamplesAround
// and moves only the stratified ones: the regenerated ones must be exactly DepthGuidedSamples' own.
TEST(DepthGuidedSampler, GaussianPartAloneIsTheSameDraws) {
  DepthGuidedConfig<float> config;
  config.xi = 0.7f;
  config.gaussian_samples = 16;
  config.stratified_samples = 8;
  const int n = config.gaussian_samples + config.stratified_samples;
  const base::CounterRng<float> uniform(11, 5);
  std::vector<float> s(n), delta(n), parts(n);
  DepthGuidedSamples(2.0f, 9.0f, 4.5f, config, uniform, s.data(), delta.data());
  StratifiedSamples(2.0f, 9.0f, config.stratified_samples, uniform, parts.data(), delta.data());
  GaussianSamplesAround(2.0f, 9.0f, 4.5f, config.xi, config.gaussian_samples, uniform,
                        unsigned(config.stratified_samples), parts.data() + config.stratified_samples);
  SortAscending(parts.data(), n);
  EXPECT_EQ(parts, s);
}

}  // namespace
}  // namespace endorecon::render
