// Ray sampling and uncertainty scores at the extremes (issue 6 §1): empty and huge depth ranges,
// zero-width Gaussians, constant and non-finite variances. Every sample position, interval and
// score stays finite and inside its range.
#include <gtest/gtest.h>

#include <cfloat>
#include <cmath>
#include <vector>

#include "worker/engine/base/counter_rng.h"
#include "worker/engine/render/adaptive_sampler.h"
#include "worker/engine/render/depth_guided_sampler.h"
#include "worker/engine/render/sample_score.h"
#include "worker/engine/render/stratified_sampler.h"

namespace endorecon::render {
namespace {

void ExpectValidSamples(const std::vector<float>& s, const std::vector<float>& delta, float near, float far,
                        const char* what) {
  for (std::size_t j = 0; j < s.size(); ++j) {
    ASSERT_TRUE(std::isfinite(s[j])) << what << " " << j;
    ASSERT_TRUE(std::isfinite(delta[j])) << what << " " << j;
    EXPECT_GE(s[j], near) << what;
    EXPECT_LE(s[j], far) << what;
    EXPECT_GE(delta[j], 0.0f) << what;
    if (j > 0) {
      EXPECT_GE(s[j], s[j - 1]) << what;
    }
  }
}

TEST(SamplingExtremes, EmptyAndHugeDepthRanges) {
  const float ranges[][2] = {{3.0f, 3.0f}, {0.0f, 1e-9f}, {0.0f, 1e30f}, {1e30f, 3e30f}};
  const base::CounterRng<float> rng(1, 2);
  for (const auto& r : ranges) {
    std::vector<float> s(32), delta(32), coarse(32), score(32, 1.0f);
    StratifiedSamples(r[0], r[1], 32, rng, s.data(), delta.data());
    ExpectValidSamples(s, delta, r[0], r[1], "stratified");
    coarse = s;
    score[7] = 1e30f;
    AdaptiveSamples(coarse.data(), score.data(), 32, r[0], r[1], 0.1f, 32, rng, s.data(), delta.data());
    ExpectValidSamples(s, delta, r[0], r[1], "adaptive");
    const DepthGuidedConfig<float> config{0.5f * (r[1] - r[0]), 24, 8};
    DepthGuidedSamples(r[0], r[1], 0.5f * (r[0] + r[1]), config, rng, s.data(), delta.data());
    ExpectValidSamples(s, delta, r[0], r[1], "depth-guided");
  }
}

TEST(SamplingExtremes, ZeroWidthGaussianPutsEverySampleOnThePrior) {
  const DepthGuidedConfig<float> config{0.0f, 16, 0};
  std::vector<float> s(16), delta(16);
  DepthGuidedSamples(1.0f, 5.0f, 2.5f, config, base::CounterRng<float>(4, 4), s.data(), delta.data());
  ExpectValidSamples(s, delta, 1.0f, 5.0f, "xi = 0");
  for (float x : s) EXPECT_EQ(x, 2.5f);
}

TEST(SamplingExtremes, MinMaxNormalisationOfDegenerateVectors) {
  // Constant, denormal, huge, with NaN and with infinity: every output in [0, 1], never NaN.
  const float vectors[][4] = {
      {0, 0, 0, 0},   {7, 7, 7, 7},        {1e-40f, 2e-40f, 0, 1e-45f}, {FLT_MAX, -FLT_MAX, 0, 1},
      {NAN, 1, 2, 3}, {INFINITY, 1, 2, 3}, {-INFINITY, INFINITY, 0, 0}};
  for (const auto& v : vectors) {
    float out[4];
    for (float eps : {0.0f, 1e-8f}) {
      MinMaxNormalize(v, 4, eps, out);
      for (float x : out) {
        EXPECT_TRUE(std::isfinite(x));
        EXPECT_GE(x, 0.0f);
        EXPECT_LE(x, 1.0f);
      }
    }
  }
  const float constant[3] = {0.25f, 0.25f, 0.25f};
  float out[3];
  MinMaxNormalize(constant, 3, 1e-8f, out);
  for (float x : out) EXPECT_EQ(x, 0.0f);
}

TEST(SamplingExtremes, RayScoreWithTinyOrNoWeight) {
  const float var_density[2] = {1e20f, 3.0f}, var_color[2] = {1e20f, 1.0f};
  const float no_weight[2] = {0.0f, 0.0f}, denormal[2] = {1e-44f, 1e-44f};
  EXPECT_EQ(RayScore(no_weight, var_density, var_color, 2, 0.5f), 0.0f);
  const float tiny = RayScore(denormal, var_density, var_color, 2, 0.5f);
  EXPECT_TRUE(std::isfinite(tiny));
  EXPECT_GT(tiny, 0.0f);
}

}  // namespace
}  // namespace endorecon::render
