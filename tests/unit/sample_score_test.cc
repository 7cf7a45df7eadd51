#include "worker/engine/render/sample_score.h"

#include <gtest/gtest.h>

#include <cmath>

namespace endorecon::render {
namespace {

TEST(SampleScore, MinMaxNormalisationMapsOntoUnitRange) {
  const double v[4] = {2, 6, 4, 3};
  double out[4];
  MinMaxNormalize(v, 4, 0.0, out);
  EXPECT_DOUBLE_EQ(out[0], 0.0);
  EXPECT_DOUBLE_EQ(out[1], 1.0);
  EXPECT_DOUBLE_EQ(out[2], 0.5);
  EXPECT_DOUBLE_EQ(out[3], 0.25);
  MinMaxNormalize(v, 4, 4.0, out);  // eps widens the denominator: (v - 2) / 8
  EXPECT_DOUBLE_EQ(out[1], 0.5);
}

TEST(SampleScore, ConstantVectorNormalisesToZero) {
  for (double c : {0.0, 1e-30, 3.0, 1e30}) {
    const double v[5] = {c, c, c, c, c};
    double out[5];
    for (double eps : {0.0, 1e-8}) {
      MinMaxNormalize(v, 5, eps, out);
      for (double x : out) EXPECT_EQ(x, 0.0) << c << " " << eps;
    }
  }
}

TEST(SampleScore, SampleScoresCombineBothVariances) {
  const double var_density[3] = {1, 3, 2}, var_color[3] = {0.5, 0.1, 0.9};
  double score[3];
  SampleScores(var_density, var_color, 3, 0.5, 0.0, score);
  EXPECT_DOUBLE_EQ(score[0], 0.0 + 0.5 * 0.5);
  EXPECT_DOUBLE_EQ(score[1], 1.0 + 0.0);
  EXPECT_DOUBLE_EQ(score[2], 0.5 + 0.5 * 1.0);
}

TEST(SampleScore, RayScoreIsTheWeightedMeanOfRawVariances) {
  const double w[3] = {0.2, 0.6, 0.0}, var_density[3] = {1, 3, 100}, var_color[3] = {2, 4, 100};
  // (0.2 (1 + 0.5*2) + 0.6 (3 + 0.5*4)) / 0.8 = (0.4 + 3.0) / 0.8
  EXPECT_DOUBLE_EQ(RayScore(w, var_density, var_color, 3, 0.5), 3.4 / 0.8);
}

TEST(SampleScore, RayThatHitsNothingScoresZero) {
  const double w[3] = {0, 0, 0}, var[3] = {1, 2, 3};
  EXPECT_EQ(RayScore(w, var, var, 3, 1.0), 0.0);
  EXPECT_EQ(RayScore(w, var, var, 0, 1.0), 0.0);
}

}  // namespace
}  // namespace endorecon::render
