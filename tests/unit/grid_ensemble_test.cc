#include "worker/engine/field/grid_ensemble.h"

#include <gtest/gtest.h>

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
  const GridEnsemble<double> e(SmallConfig());
  ASSERT_EQ(e.grids(), 2);
  EXPECT_EQ(e.grid(0).levels(), 3);
  EXPECT_EQ(e.grid(1).levels(), 2);
  EXPECT_EQ(e.feature_dim(), 6);
  EXPECT_EQ(e.output_dim(), 12);
  EXPECT_EQ(e.param_count(), e.grid(0).param_count() + e.grid(1).param_count());
  const std::vector<double> params = RandomValues(e.param_count(), -1, 1, 1);
  const std::vector<double> pos = RandomValues(30, 0, 1, 2);
  std::vector<double> feats(10 * 12, 5.0);
  e.Forward(params.data(), pos.data(), 10, feats.data());
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
  const GridEnsemble<double> e(SmallConfig());
  const int n = 12, width = e.output_dim();
  std::vector<double> params = RandomValues(e.param_count(), -1, 1, 3);
  std::vector<double> pos = RandomValues(3 * n, 0.02, 0.98, 4);
  const std::vector<double> w = RandomValues(static_cast<std::size_t>(n) * width, -1, 1, 5);
  auto loss = [&] {
    std::vector<double> feats(static_cast<std::size_t>(n) * width);
    e.Forward(params.data(), pos.data(), n, feats.data());
    return Dot(w, feats);
  };
  std::vector<double> grads(params.size(), 0.0), dpos(pos.size(), 0.0);
  for (int g = 0; g < e.grids(); ++g) {
    for (int l = 0; l < e.grid(g).levels(); ++l) {
      e.BackwardLevel(g, l, pos.data(), n, w.data() + g * e.feature_dim() + 2 * l, width, nullptr,
                      grads.data(), params.data(), dpos.data());
    }
  }
  EXPECT_GT(
      ExpectGradientMatches(params.data(), grads.data(), SomeIndices(params.size(), 300, 1), loss, "params"),
      50);
  EXPECT_EQ(
      ExpectGradientMatches(pos.data(), dpos.data(), SomeIndices(pos.size(), pos.size(), 2), loss, "pos"),
      3 * n);
}

}  // namespace
}  // namespace endorecon::field
