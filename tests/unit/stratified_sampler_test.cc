#include "worker/engine/render/stratified_sampler.h"

#include <gtest/gtest.h>

#include <vector>

#include "worker/engine/base/counter_rng.h"

namespace endorecon::render {
namespace {

TEST(StratifiedSampler, HalfJitterGivesBinCentres) {
  double s[4], delta[4];
  StratifiedSamples(
      2.0, 6.0, 4, [](unsigned) { return 0.5; }, s, delta);
  const double centres[4] = {2.5, 3.5, 4.5, 5.5};
  for (int j = 0; j < 4; ++j) {
    EXPECT_DOUBLE_EQ(s[j], centres[j]);
    EXPECT_DOUBLE_EQ(delta[j], 1.0);
  }
}

TEST(StratifiedSampler, OneSamplePerBinAndIntervalsTileTheRange) {
  const int n = 64;
  const float near = 0.3f, far = 7.9f;
  std::vector<float> s(n), delta(n);
  StratifiedSamples(near, far, n, base::CounterRng<float>(5, 11), s.data(), delta.data());
  float edge = near, total = 0;
  for (int j = 0; j < n; ++j) {
    EXPECT_GE(s[j], edge);
    EXPECT_LE(s[j], edge + delta[j]);
    EXPECT_NEAR(delta[j], (far - near) / n, 1e-5f);
    if (j > 0) {
      EXPECT_GE(s[j], s[j - 1]);
    }
    edge += delta[j];
    total += delta[j];
  }
  EXPECT_NEAR(total, far - near, 1e-5f);
  // Jittered: the offsets within the first two bins differ.
  EXPECT_NE(s[0] - near, s[1] - near - delta[0]);
}

TEST(StratifiedSampler, DrawIndicesStartAtFirstDraw) {
  double s[3], delta[3];
  StratifiedSamples(
      0.0, 3.0, 3, [](unsigned i) { return i == 10 ? 0.0 : 0.25 * (i - 10); }, s, delta, 10);
  EXPECT_DOUBLE_EQ(s[0], 0.0);
  EXPECT_DOUBLE_EQ(s[1], 1.25);
  EXPECT_DOUBLE_EQ(s[2], 2.5);
}

}  // namespace
}  // namespace endorecon::render
