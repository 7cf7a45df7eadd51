#include "worker/engine/field/temporal_blend.h"

#include <gtest/gtest.h>

#include <vector>

#include "tests/unit/gradient_check.h"

namespace endorecon::field {
namespace {

using testing::Dot;
using testing::ExpectGradientMatches;
using testing::RandomValues;
using testing::SomeIndices;

constexpr int kGrids = 3, kHidden = 5;

struct BlendRun {
  std::vector<double> hidden, beta;
};

BlendRun Forward(TemporalBlend<double>& blend, const std::vector<double>& params,
                 const std::vector<double>& t) {
  const int n = static_cast<int>(t.size());
  BlendRun run;
  run.hidden.resize(static_cast<std::size_t>(n) * kHidden);
  run.beta.resize(static_cast<std::size_t>(n) * kGrids);
  blend.Forward(params.data(), {n, t.data()}, {run.hidden.data(), run.beta.data()}, {});
  return run;
}

TEST(TemporalBlendTest, StartsAsAnEvenBlend) {
  TemporalBlend<double> blend(kGrids, kHidden);
  std::vector<double> params(blend.param_count());
  blend.Init(params.data(), 1);
  const BlendRun run = Forward(blend, params, {0.0, 0.3, 1.0});
  for (double b : run.beta) EXPECT_DOUBLE_EQ(b, 1.0 / kGrids);
}

TEST(TemporalBlendTest, WeightsSumToOneAndVaryInTime) {
  TemporalBlend<double> blend(kGrids, kHidden);
  const std::vector<double> params = RandomValues(blend.param_count(), -2, 2, 3);
  const BlendRun run = Forward(blend, params, RandomValues(50, 0, 1, 4));
  for (int s = 0; s < 50; ++s) {
    double sum = 0;
    for (int i = 0; i < kGrids; ++i) {
      EXPECT_GT(run.beta[s * kGrids + i], 0.0);
      sum += run.beta[s * kGrids + i];
    }
    EXPECT_NEAR(sum, 1.0, 1e-14);
  }
  EXPECT_NE(run.beta[0], run.beta[kGrids]);
}

TEST(TemporalBlendTest, GradientsMatchFiniteDifferences) {
  TemporalBlend<double> blend(kGrids, kHidden);
  const int n = 13;
  std::vector<double> params = RandomValues(blend.param_count(), -1, 1, 5);
  const std::vector<double> t = RandomValues(n, 0, 1, 6);
  const std::vector<double> w = RandomValues(static_cast<std::size_t>(n) * kGrids, -1, 1, 8);
  BlendRun run = Forward(blend, params, t);
  std::vector<double> grads(params.size(), 0.0);
  blend.Backward(params.data(), {n, t.data()}, {run.hidden.data(), run.beta.data()}, {w.data()}, grads.data(),
                 {}, {});
  auto loss = [&] { return Dot(w, Forward(blend, params, t).beta); };
  EXPECT_GT(ExpectGradientMatches(params.data(), grads.data(), SomeIndices(params.size(), params.size(), 1),
                                  loss, "params"),
            10);
}

}  // namespace
}  // namespace endorecon::field
