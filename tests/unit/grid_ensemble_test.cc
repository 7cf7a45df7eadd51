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

TEST(GridEnsembleTest, PadsGridsThatLeftLevelsOut) {
  GridEnsemble<double> e(SmallConfig());
  ASSERT_EQ(e.grids(), 2);
  EXPECT_EQ(e.grid(0).levels(), 3);
  EXPECT_EQ(e.grid(1).levels(), 2);
  EXPECT_EQ(e.feature_dim(), 6);
  EXPECT_EQ(e.output_dim(), 12);
  EXPECT_EQ(e.param_count(), e.grid(0).param_count() + e.grid(1).param_count());
  const std::vector<double> params = RandomValues(e.param_count(), -1, 1, 1);
  const std::vector<double> pos = RandomValues(30, 0, 1, 2);
  std::vector<double> feats(10 * 12, 5.0);
  e.Forward(params.data(), {10, pos.data()}, {feats.data()}, {});
  for (int s = 0; s < 10; ++s) {
    EXPECT_EQ(feats[s * 12 + 10], 0.0);
    EXPECT_EQ(feats[s * 12 + 11], 0.0);
    EXPECT_NE(feats[s * 12 + 9], 0.0);
  }
}

TEST(GridEnsembleTest, RejectsMismatchedLists) {
  GridEnsembleConfig c = SmallConfig();
  c.scales = {1.5};
  EXPECT_THROW(GridEnsemble<float>{c}, Error);
}

TEST(GridEnsembleTest, GradientsMatchFiniteDifferences) {
  GridEnsemble<double> e(SmallConfig());
  const int n = 12, width = e.output_dim();
  std::vector<double> params = RandomValues(e.param_count(), -1, 1, 3);
  std::vector<double> pos = RandomValues(3 * n, 0.02, 0.98, 4);
  const std::vector<double> w = RandomValues(static_cast<std::size_t>(n) * width, -1, 1, 5);
  std::vector<double> feats(static_cast<std::size_t>(n) * width);
  auto loss = [&] {
    e.Forward(params.data(), {n, pos.data()}, {feats.data()}, {});
    return Dot(w, feats);
  };
  loss();
  std::vector<double> grads(params.size(), 0.0), dpos(pos.size(), 0.0);
  e.Backward(params.data(), {n, pos.data()}, {feats.data()}, {w.data()}, grads.data(), {dpos.data()}, {});
  EXPECT_GT(
      ExpectGradientMatches(params.data(), grads.data(), SomeIndices(params.size(), 300, 1), loss, "params"),
      50);
  EXPECT_EQ(
      ExpectGradientMatches(pos.data(), dpos.data(), SomeIndices(pos.size(), pos.size(), 2), loss, "pos"),
      3 * n);
}

// Many samples (several tasks, the position gradient summed over fixed groups of levels): the
// gradients equal the sum of those of the batch's parts.
TEST(GridEnsembleTest, BatchGradientsAreTheSumOverItsParts) {
  GridEnsemble<double> e(SmallConfig());
  const int n = 5000, split = 2100, width = e.output_dim();
  const std::vector<double> params = RandomValues(e.param_count(), -1, 1, 6);
  const std::vector<double> pos = RandomValues(3 * n, 0.01, 0.99, 7);
  const std::vector<double> w = RandomValues(static_cast<std::size_t>(n) * width, -1, 1, 8);
  std::vector<double> feats(static_cast<std::size_t>(n) * width), grads(params.size(), 0.0), dpos(pos.size());
  e.Backward(params.data(), {n, pos.data()}, {feats.data()}, {w.data()}, grads.data(), {dpos.data()}, {});
  std::vector<double> parts(params.size(), 0.0), dpos_parts(pos.size());
  for (const auto& [first, count] : {std::pair{0, split}, std::pair{split, n - split}}) {
    e.Backward(params.data(), {count, pos.data() + 3 * first}, {feats.data()}, {w.data() + first * width},
               parts.data(), {dpos_parts.data() + 3 * first}, {});
  }
  for (std::size_t i = 0; i < grads.size(); ++i)
    ASSERT_NEAR(grads[i], parts[i], 1e-9 * (1 + std::abs(parts[i]))) << i;
  for (std::size_t i = 0; i < dpos.size(); ++i) ASSERT_NEAR(dpos[i], dpos_parts[i], 1e-12) << i;
}

}  // namespace
}  // namespace endorecon::field
