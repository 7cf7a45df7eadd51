#include "worker/engine/field/grid_ensemble.h"

#include <gtest/gtest.h>

#include <cmath>
#include <utility>
#include <vector>

#include "common/error.h"
#include "tests/unit/gradient_check.h"

namespace endorecon::field {
namespace {

using testing::Dot;
using testing::ExpectGradientMatches;
using testing::RandomValues;
using testing::SomeIndices;

GridEnsembleConfig SmallConfig() {
  GridEnsembleConfig c;
  c.base_resolutions = {2, 4};
  c.scales = {1.5, 2.0};
  c.levels = 3;
  c.features = 2;
  c.log2_table = 6;
  c.max_resolution = 10;  // grid 1 keeps 4, 8 and drops 16
  return c;
}

// Weights of a blend: positive, each row summing to 1.
std::vector<double> Weights(int n, int grids, std::uint64_t seed) {
  std::vector<double> beta = RandomValues(static_cast<std::size_t>(n) * grids, 0.1, 1, seed);
  for (int s = 0; s < n; ++s) {
    double sum = 0;
    for (int g = 0; g < grids; ++g) sum += beta[s * grids + g];
    for (int g = 0; g < grids; ++g) beta[s * grids + g] /= sum;
  }
  return beta;
}

TEST(GridEnsembleTest, PadsGridsThatLeftLevelsOutAndBlends) {
  GridEnsemble<double> e(SmallConfig());
  ASSERT_EQ(e.grids(), 2);
  EXPECT_EQ(e.grid(0).levels(), 3);
  EXPECT_EQ(e.grid(1).levels(), 2);
  EXPECT_EQ(e.feature_dim(), 6);
  EXPECT_EQ(e.output_dim(), 12);
  EXPECT_EQ(e.param_count(), e.grid(0).param_count() + e.grid(1).param_count());
  const std::vector<double> params = RandomValues(e.param_count(), -1, 1, 1);
  const std::vector<double> pos = RandomValues(30, 0, 1, 2);
  const std::vector<double> beta = Weights(10, 2, 3);
  std::vector<double> feats(10 * 12, 5.0), f(10 * 6);
  e.Forward(params.data(), {10, pos.data(), beta.data()}, {feats.data(), f.data()}, {});
  for (int s = 0; s < 10; ++s) {
    EXPECT_EQ(feats[s * 12 + 10], 0.0);
    EXPECT_EQ(feats[s * 12 + 11], 0.0);
    EXPECT_NE(feats[s * 12 + 9], 0.0);
    for (int j = 0; j < 6; ++j) {
      EXPECT_NEAR(f[s * 6 + j], beta[2 * s] * feats[s * 12 + j] + beta[2 * s + 1] * feats[s * 12 + 6 + j],
                  1e-15);
    }
  }
}

TEST(GridEnsembleTest, RejectsMismatchedLists) {
  GridEnsembleConfig c = SmallConfig();
  c.scales = {1.5};
  EXPECT_THROW(GridEnsemble<float>{c}, Error);
}

TEST(GridEnsembleTest, GradientsMatchFiniteDifferences) {
  GridEnsemble<double> e(SmallConfig());
  const int n = 12, d = e.feature_dim();
  std::vector<double> params = RandomValues(e.param_count(), -1, 1, 3);
  std::vector<double> pos = RandomValues(3 * n, 0.02, 0.98, 4);
  std::vector<double> beta = Weights(n, e.grids(), 9);
  const std::vector<double> w = RandomValues(static_cast<std::size_t>(n) * d, -1, 1, 5);
  std::vector<double> feats(static_cast<std::size_t>(n) * e.output_dim()), f(static_cast<std::size_t>(n) * d);
  auto loss = [&] {
    e.Forward(params.data(), {n, pos.data(), beta.data()}, {feats.data(), f.data()}, {});
    return Dot(w, f);
  };
  loss();
  std::vector<double> grads(params.size(), 0.0), dpos(pos.size(), 0.0), dbeta(beta.size(), 0.0);
  e.Backward(params.data(), {n, pos.data(), beta.data()}, {feats.data(), f.data()}, {w.data()}, grads.data(),
             {dpos.data(), dbeta.data()}, {});
  EXPECT_GT(
      ExpectGradientMatches(params.data(), grads.data(), SomeIndices(params.size(), 300, 1), loss, "params"),
      50);
  EXPECT_EQ(
      ExpectGradientMatches(pos.data(), dpos.data(), SomeIndices(pos.size(), pos.size(), 2), loss, "pos"),
      3 * n);
  EXPECT_EQ(ExpectGradientMatches(beta.data(), dbeta.data(), SomeIndices(beta.size(), beta.size(), 3), loss,
                                  "beta"),
            static_cast<int>(beta.size()));
}

// Many samples (several tasks, the position gradient summed over fixed groups of levels): the
// gradients equal the sum of those of the batch's parts.
TEST(GridEnsembleTest, BatchGradientsAreTheSumOverItsParts) {
  GridEnsemble<double> e(SmallConfig());
  const int n = 5000, split = 2100, d = e.feature_dim(), g = e.grids();
  const std::vector<double> params = RandomValues(e.param_count(), -1, 1, 6);
  const std::vector<double> pos = RandomValues(3 * n, 0.01, 0.99, 7);
  const std::vector<double> beta = Weights(n, g, 10);
  const std::vector<double> w = RandomValues(static_cast<std::size_t>(n) * d, -1, 1, 8);
  std::vector<double> feats(static_cast<std::size_t>(n) * e.output_dim()), f(static_cast<std::size_t>(n) * d);
  e.Forward(params.data(), {n, pos.data(), beta.data()}, {feats.data(), f.data()}, {});
  std::vector<double> grads(params.size(), 0.0), dpos(pos.size()), dbeta(beta.size());
  e.Backward(params.data(), {n, pos.data(), beta.data()}, {feats.data(), f.data()}, {w.data()}, grads.data(),
             {dpos.data(), dbeta.data()}, {});
  std::vector<double> parts(params.size(), 0.0), dpos_parts(pos.size()), dbeta_parts(beta.size());
  for (const auto& [first, count] : {std::pair{0, split}, std::pair{split, n - split}}) {
    e.Backward(params.data(), {count, pos.data() + 3 * first, beta.data() + g * first},
               {feats.data() + first * e.output_dim(), f.data() + first * d}, {w.data() + first * d},
               parts.data(), {dpos_parts.data() + 3 * first, dbeta_parts.data() + g * first}, {});
  }
  for (std::size_t i = 0; i < grads.size(); ++i)
    ASSERT_NEAR(grads[i], parts[i], 1e-9 * (1 + std::abs(parts[i]))) << i;
  for (std::size_t i = 0; i < dpos.size(); ++i) ASSERT_NEAR(dpos[i], dpos_parts[i], 1e-12) << i;
  for (std::size_t i = 0; i < dbeta.size(); ++i) ASSERT_EQ(dbeta[i], dbeta_parts[i]) << i;
}

}  // namespace
}  // namespace endorecon::field
