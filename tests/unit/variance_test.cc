#include "worker/engine/field/variance.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "tests/unit/central_difference.h"

namespace endorecon::field {
namespace {

TEST(VarianceTest, IsSoftplusPlusEpsilon) {
  for (double l : {-5.0, -1.0, 0.0, 0.5, 3.0, 20.0}) {
    EXPECT_NEAR(VarianceFromLogVar(l, 1e-3), std::log1p(std::exp(l)) + 1e-3, 1e-14) << l;
  }
  EXPECT_DOUBLE_EQ(VarianceFromLogVar(0.0, 0.0), std::log(2.0));
}

TEST(VarianceTest, FiniteAndAccurateAtTheExtremes) {
  for (float l : {-80.0f, -200.0f, 80.0f, 1000.0f, std::numeric_limits<float>::max()}) {
    const float v = VarianceFromLogVar(l, 0.0f);
    EXPECT_TRUE(std::isfinite(v)) << l;
    EXPECT_TRUE(std::isfinite(VarianceFromLogVarGrad(l))) << l;
  }
  EXPECT_FLOAT_EQ(VarianceFromLogVar(80.0f, 0.0f), 80.0f);
  EXPECT_FLOAT_EQ(VarianceFromLogVar(-80.0f, 0.0f), std::exp(-80.0f));  // no loss to log1p(1 + tiny)
  EXPECT_DOUBLE_EQ(VarianceFromLogVar(-700.0, 0.0), std::exp(-700.0));
  EXPECT_FLOAT_EQ(VarianceFromLogVar(-1000.0f, 1e-4f), 1e-4f);
  EXPECT_EQ(VarianceFromLogVarGrad(-1000.0f), 0.0f);
  EXPECT_EQ(VarianceFromLogVarGrad(1000.0f), 1.0f);
}

TEST(VarianceTest, GradientIsSigmoid) {
  for (double l : {-30.0, -4.0, -0.3, 0.0, 2.0, 25.0}) {
    double x = l;
    const double numeric = testing::CentralDifference(x, 1e-6, [&] { return VarianceFromLogVar(x, 0.01); });
    EXPECT_NEAR(VarianceFromLogVarGrad(l), numeric, 1e-8 * std::fmax(1.0, std::fabs(numeric))) << l;
    EXPECT_NEAR(VarianceFromLogVarGrad(l), 1 / (1 + std::exp(-l)), 1e-15) << l;
  }
}

}  // namespace
}  // namespace endorecon::field
