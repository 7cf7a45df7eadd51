#include "worker/engine/field/deformation.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "common/error.h"
#include "tests/unit/gradient_check.h"

namespace endorecon::field {
namespace {

using testing::Dot;
using testing::ExpectGradientMatches;
using testing::RandomValues;
using testing::SomeIndices;

DeformationConfig SmallConfig() {
  DeformationConfig c;
  c.resolution = 3;
  c.time_knots = 4;
  return c;
}

std::vector<double> Canonical(Deformation<double>& deform, const std::vector<double>& params,
                              const std::vector<double>& pos, const std::vector<double>& t) {
  std::vector<double> x0(pos.size());
  deform.Forward(params.data(), {static_cast<int>(t.size()), pos.data(), t.data()}, {x0.data()}, {});
  return x0;
}

TEST(DeformationTest, StartsAtZeroMotion) {
  Deformation<double> deform(SmallConfig());
  std::vector<double> params(deform.param_count(), 1.0);
  deform.Init(params.data(), 7);
  const std::vector<double> pos = RandomValues(30, 0, 1, 1), t = RandomValues(10, 0, 1, 2);
  EXPECT_EQ(Canonical(deform, params, pos, t), pos);
}

TEST(DeformationTest, IsExactlyZeroAtTimeZero) {
  Deformation<double> deform(SmallConfig());
  const std::vector<double> params = RandomValues(deform.param_count(), -1, 1, 3);
  const std::vector<double> pos = RandomValues(30, 0, 1, 4);
  EXPECT_EQ(Canonical(deform, params, pos, std::vector<double>(10, 0.0)), pos);
  EXPECT_NE(Canonical(deform, params, pos, std::vector<double>(10, 0.5)), pos);
}

TEST(DeformationTest, ParameterCountIsKnotsTimesVertices) {
  EXPECT_EQ(Deformation<float>(SmallConfig()).param_count(), 4u * 64u * 3u);
  DeformationConfig bad = SmallConfig();
  bad.time_knots = 0;
  EXPECT_THROW(Deformation<float>{bad}, Error);
}

TEST(DeformationTest, NonFiniteInputsStayFinite) {
  Deformation<double> deform(SmallConfig());
  const std::vector<double> params = RandomValues(deform.param_count(), -1, 1, 5);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  const std::vector<double> pos = {0.5, 0.5, 0.5, 0.2, 0.2, 0.2};
  const auto x0 = Canonical(deform, params, pos, {nan, inf});
  for (double v : x0) EXPECT_TRUE(std::isfinite(v));
  // NaN time reads as t = 0 (no motion); +Inf as t = 1.
  EXPECT_EQ(x0[0], 0.5);
  EXPECT_EQ(Canonical(deform, params, pos, {0.0, 1.0}), x0);
}

TEST(DeformationTest, GradientsMatchFiniteDifferences) {
  Deformation<double> deform(SmallConfig());
  const int n = 20;
  std::vector<double> params = RandomValues(deform.param_count(), -0.2, 0.2, 6);
  std::vector<double> pos = RandomValues(3 * n, 0.02, 0.98, 7);
  std::vector<double> t = RandomValues(n, 0, 1, 8);
  t[0] = 0.0;
  t[1] = 1.0;
  t[2] = 0.5;  // exactly on a knot
  const std::vector<double> w = RandomValues(3 * n, -1, 1, 9);
  std::vector<double> grads(params.size(), 0.0), dpos(pos.size(), 0.0),
      x0 = Canonical(deform, params, pos, t);
  deform.Backward(params.data(), {n, pos.data(), t.data()}, {x0.data()}, {w.data()}, grads.data(),
                  {dpos.data()}, {});
  auto loss = [&] { return Dot(w, Canonical(deform, params, pos, t)); };
  EXPECT_GT(ExpectGradientMatches(params.data(), grads.data(), SomeIndices(params.size(), params.size(), 1),
                                  loss, "params"),
            200);
  EXPECT_EQ(
      ExpectGradientMatches(pos.data(), dpos.data(), SomeIndices(pos.size(), pos.size(), 2), loss, "pos"),
      3 * n);
}

// The weights a linear fit reads (train/flow_start.h) are the ones the forward pass blends with.
TEST(DeformationTest, WeightsBlendAsTheForwardPass) {
  Deformation<double> deform(SmallConfig());
  const DeformationLayout layout = deform.layout();
  const std::vector<double> params = RandomValues(deform.param_count(), -0.2, 0.2, 3);
  const std::vector<double> pos = RandomValues(60, -0.1, 1.1, 4), t = RandomValues(20, -0.05, 1.05, 5);
  const std::vector<double> x0 = Canonical(deform, params, pos, t);
  for (std::size_t i = 0; i < t.size(); ++i) {
    std::size_t vertex[16];
    double weight[16];
    const int count = DeformWeights(layout, &pos[3 * i], t[i], vertex, weight);
    ASSERT_TRUE(count == 8 || count == 16);
    for (int a = 0; a < 3; ++a) {
      double dx = 0;
      for (int j = 0; j < count; ++j) {
        ASSERT_LT(vertex[j] * 3 + std::size_t(a), params.size());
        dx += weight[j] * params[vertex[j] * 3 + std::size_t(a)];
      }
      EXPECT_NEAR(pos[3 * i + a] + dx, x0[3 * i + a], 1e-12) << "sample " << i << " axis " << a;
    }
  }
}

}  // namespace
}  // namespace endorecon::field
