#include "worker/engine/base/counter_rng.h"

#include <gtest/gtest.h>

#include <cmath>

namespace endorecon::base {
namespace {

TEST(CounterRng, SameKeyGivesSameDrawsAndStreamsDiffer) {
  const CounterRng<float> a(42, 7), b(42, 7), other_stream(42, 8), other_seed(43, 7);
  int same_as_other_stream = 0, same_as_other_seed = 0;
  for (unsigned i = 0; i < 1000; ++i) {
    EXPECT_EQ(a(i), b(i));
    same_as_other_stream += a(i) == other_stream(i);
    same_as_other_seed += a(i) == other_seed(i);
  }
  EXPECT_LE(same_as_other_stream, 2);
  EXPECT_LE(same_as_other_seed, 2);
}

TEST(CounterRng, UniformMomentsAndRange) {
  // 200k draws of U[0, 1): mean 1/2 and variance 1/12 within ~5 standard errors.
  const CounterRng<double> rng(1, 2);
  const int n = 200000;
  double sum = 0, sum_sq = 0, lo = 1, hi = 0;
  for (int i = 0; i < n; ++i) {
    const double u = rng(static_cast<unsigned>(i));
    sum += u;
    sum_sq += u * u;
    lo = std::fmin(lo, u);
    hi = std::fmax(hi, u);
  }
  const double mean = sum / n;
  EXPECT_NEAR(mean, 0.5, 5 * std::sqrt(1.0 / 12 / n));
  EXPECT_NEAR(sum_sq / n - mean * mean, 1.0 / 12, 2e-3);
  EXPECT_GE(lo, 0.0);
  EXPECT_LT(hi, 1.0);
  EXPECT_LT(lo, 1e-3);
  EXPECT_GT(hi, 1 - 1e-3);
}

TEST(CounterRng, FloatUniformNeverReachesOne) {
  EXPECT_LT(UniformFromBits<float>(~0ull), 1.0f);
  EXPECT_LT(UniformFromBits<double>(~0ull), 1.0);
  EXPECT_EQ(UniformFromBits<float>(0), 0.0f);
}

TEST(CounterRng, BoxMullerGivesStandardNormal) {
  const CounterRng<double> rng(9, 0);
  const int n = 100000;
  double sum = 0, sum_sq = 0;
  for (int i = 0; i < n; ++i) {
    const double z = NormalFromUniforms(rng(2 * i), rng(2 * i + 1));
    ASSERT_TRUE(std::isfinite(z));
    sum += z;
    sum_sq += z * z;
  }
  EXPECT_NEAR(sum / n, 0.0, 5 / std::sqrt(n));
  EXPECT_NEAR(sum_sq / n, 1.0, 0.02);
  EXPECT_TRUE(std::isfinite(NormalFromUniforms(0.0, 0.0)));
  EXPECT_TRUE(std::isfinite(NormalFromUniforms(UniformFromBits<float>(~0ull), 0.5f)));
}

// StreamSeed(seed, k) is output k + 1 of the splitmix64 sequence started at `seed` (Vigna's reference
// values for seed 0), the seeds every synthetic clip's frames were drawn with.
TEST(StreamSeed, IsTheSplitmix64Sequence) {
  EXPECT_EQ(StreamSeed(0, 0), 0xe220a8397b1dcdafull);
  EXPECT_EQ(StreamSeed(0, 1), 0x6e789e6aa1b965f4ull);
  EXPECT_EQ(StreamSeed(0, 2), 0x06c45d188009454full);
}

}  // namespace
}  // namespace endorecon::base
