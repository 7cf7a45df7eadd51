#include "worker/engine/train/adam.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <sstream>

namespace endorecon::train {
namespace {

TEST(AdamTest, MinimisesAQuadraticWithPerGroupRates) {
  std::vector<float> x = {3.0f, -2.0f}, gx(2), y = {5.0f}, gy(1);
  AdamConfig config;
  config.lr = {{"x", 0.1f}, {"y", 0.0f}};
  Adam adam({{"x", x.data(), gx.data(), 2}, {"y", y.data(), gy.data(), 1}}, config);
  for (int i = 0; i < 500; ++i) {
    for (int k = 0; k < 2; ++k) gx[k] = 2 * x[k];
    gy[0] = 2 * y[0];
    ASSERT_TRUE(adam.Step(i / 500.0).finite);
  }
  EXPECT_LT(std::abs(x[0]) + std::abs(x[1]), 0.05f);
  EXPECT_EQ(y[0], 5.0f) << "a group with learning rate 0 moved";
}

TEST(AdamTest, NonFiniteGradientChangesNothingAndNamesTheGroup) {
  std::vector<float> x = {1.0f}, gx = {std::numeric_limits<float>::quiet_NaN()};
  Adam adam({{"grid", x.data(), gx.data(), 1}}, AdamConfig{});
  const AdamStepReport report = adam.Step(0.0);
  EXPECT_FALSE(report.finite);
  EXPECT_EQ(report.bad_group, "grid");
  EXPECT_EQ(x[0], 1.0f);
}

TEST(AdamTest, ClippingBoundsTheStepAndStateRoundTrips) {
  std::vector<float> x = {0.0f}, gx = {1e6f};
  AdamConfig config;
  config.clip_norm = 1.0f;
  Adam adam({{"x", x.data(), gx.data(), 1}}, config);
  EXPECT_NEAR(adam.Step(0.0).grad_norm, 1e6, 1.0);
  std::stringstream state;
  adam.Save(state);
  std::vector<float> x2 = x, g2 = {0.5f};
  gx[0] = 0.5f;
  Adam other({{"x", x2.data(), g2.data(), 1}}, config);
  other.Load(state);
  adam.Step(0.1);
  other.Step(0.1);
  EXPECT_EQ(x[0], x2[0]);
}

}  // namespace
}  // namespace endorecon::train
