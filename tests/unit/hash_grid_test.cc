#include "worker/engine/field/hash_grid.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <set>
#include <vector>

#include "common/error.h"
#include "tests/unit/gradient_check.h"

namespace endorecon::field {
namespace {

using testing::Dot;
using testing::ExpectGradientMatches;
using testing::RandomValues;
using testing::SomeIndices;

// Levels of resolution 2 (dense: 27 vertices <= 64 slots), 4 and 8 (hashed), 2 features.
HashGridConfig SmallConfig() {
  HashGridConfig c;
  c.levels = 3;
  c.features = 2;
  c.log2_table = 6;
  c.base_resolution = 2;
  c.scale = 2.0;
  return c;
}

std::vector<double> Features(const HashGrid<double>& grid, const std::vector<double>& params,
                             const std::vector<double>& pos) {
  const int n = static_cast<int>(pos.size() / 3);
  std::vector<double> feat(static_cast<std::size_t>(n) * grid.output_dim());
  grid.ForwardRows(params.data(), pos.data(), n, feat.data(), grid.output_dim());
  return feat;
}

TEST(HashGridTest, LevelsAreDenseWhereTheyFitAndHashedOtherwise) {
  const HashGrid<double> grid(SmallConfig());
  ASSERT_EQ(grid.levels(), 3);
  EXPECT_EQ(grid.level(0).res, 2u);
  EXPECT_EQ(grid.level(0).dense, 1u);
  EXPECT_EQ(grid.level(1).res, 4u);
  EXPECT_EQ(grid.level(1).dense, 0u);
  EXPECT_EQ(grid.level(2).dense, 0u);
  EXPECT_EQ(grid.level(1).entries, 64u);
  // Dense: 27 slots padded to 32, then two hashed levels of 64.
  EXPECT_EQ(grid.param_count(), (32u + 64u + 64u) * 2u);
}

TEST(HashGridTest, DenseIndexingIsOneToOne) {
  HashGridConfig c = SmallConfig();
  c.base_resolution = 3;
  const HashGrid<float> grid(c);
  const GridLevel& level = grid.level(0);
  ASSERT_EQ(level.dense, 1u);
  std::set<std::uint32_t> slots;
  for (std::uint32_t z = 0; z <= level.res; ++z) {
    for (std::uint32_t y = 0; y <= level.res; ++y) {
      for (std::uint32_t x = 0; x <= level.res; ++x) slots.insert(VertexSlot(level, x, y, z));
    }
  }
  EXPECT_EQ(slots.size(), 64u);
  EXPECT_EQ(*slots.rbegin(), 63u);
}

TEST(HashGridTest, HashUsesInstantNgpPrimes) {
  EXPECT_EQ(SpatialHash(1, 0, 0), 1u);
  EXPECT_EQ(SpatialHash(0, 1, 0), 2654435761u);
  EXPECT_EQ(SpatialHash(0, 0, 1), 805459861u);
  EXPECT_EQ(SpatialHash(3, 2, 1), 3u ^ (2u * 2654435761u) ^ 805459861u);
}

TEST(HashGridTest, ResolutionCapDropsFinerLevels) {
  HashGridConfig c;
  c.levels = 8;
  c.base_resolution = 16;
  c.scale = 2.0;
  EXPECT_EQ(LevelsUpToResolution(c, 100), 3);  // 16, 32, 64
  EXPECT_EQ(LevelsUpToResolution(c, 1), 1);    // never fewer than one
  EXPECT_EQ(LevelsUpToResolution(c, 1e9), 8);  // never more than configured
  c.max_resolution = 100;
  const HashGrid<float> grid(c);
  EXPECT_EQ(grid.levels(), 3);
  EXPECT_EQ(grid.dropped_levels(), 5);
  EXPECT_EQ(grid.output_dim(), 6);
}

TEST(HashGridTest, RejectsBadShapes) {
  HashGridConfig c = SmallConfig();
  c.features = 3;
  EXPECT_THROW(HashGrid<float>{c}, Error);
  c = SmallConfig();
  c.log2_table = 40;
  EXPECT_THROW(HashGrid<float>{c}, Error);
  c = SmallConfig();
  c.scale = 0.5;
  EXPECT_THROW(HashGrid<float>{c}, Error);
}

TEST(HashGridTest, InitIsSmallAndNotConstant) {
  const HashGrid<float> grid(SmallConfig());
  std::vector<float> params(grid.param_count());
  grid.Init(params.data(), 7);
  float lo = 1, hi = -1;
  for (float p : params) {
    lo = std::min(lo, p);
    hi = std::max(hi, p);
  }
  EXPECT_GE(lo, -1e-4f);
  EXPECT_LE(hi, 1e-4f);
  EXPECT_GT(hi - lo, 1e-4f);
}

TEST(HashGridTest, InterpolatesVertexValuesExactly) {
  HashGridConfig c = SmallConfig();
  c.levels = 1;
  const HashGrid<double> grid(c);
  std::vector<double> params(grid.param_count());
  for (std::size_t i = 0; i < params.size(); ++i) params[i] = static_cast<double>(i);
  // The vertex (1, 2, 0) of the 2-cell level sits at (0.5, 1, 0); its slot is 1 + 3 * 2 = 7.
  const auto f = Features(grid, params, {0.5, 1.0, 0.0});
  EXPECT_DOUBLE_EQ(f[0], 14.0);
  EXPECT_DOUBLE_EQ(f[1], 15.0);
  // Midway between vertices (0,0,0) and (1,0,0): the mean of slots 0 and 1.
  const auto g = Features(grid, params, {0.25, 0.0, 0.0});
  EXPECT_DOUBLE_EQ(g[0], 1.0);
}

TEST(HashGridTest, OutsideAndNonFiniteInputsReadTheClampedCell) {
  const HashGrid<double> grid(SmallConfig());
  std::vector<double> params = RandomValues(grid.param_count(), -1, 1, 3);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  const auto bad = Features(grid, params, {-5.0, 7.0, nan, inf, -inf, 0.5, 1e300, -1e300, 0.25});
  const auto good = Features(grid, params, {0.0, 1.0, 0.0, 1.0, 0.0, 0.5, 1.0, 0.0, 0.25});
  ASSERT_EQ(bad.size(), good.size());
  for (std::size_t i = 0; i < bad.size(); ++i) EXPECT_EQ(bad[i], good[i]) << i;

  // No gradient flows into a clamped coordinate.
  const std::vector<double> pos = {-5.0, 0.3, nan};
  const std::vector<double> dfeat(grid.output_dim(), 1.0);
  std::vector<double> grads(grid.param_count(), 0.0), dpos(3, 0.0);
  for (int l = 0; l < grid.levels(); ++l) {
    grid.BackwardLevel(l, pos.data(), 1, dfeat.data() + 2 * l, grid.output_dim(), nullptr, grads.data(),
                       params.data(), dpos.data());
  }
  EXPECT_EQ(dpos[0], 0.0);
  EXPECT_NE(dpos[1], 0.0);
  EXPECT_EQ(dpos[2], 0.0);
}

TEST(HashGridTest, TableGradientMatchesFiniteDifferences) {
  const HashGrid<double> grid(SmallConfig());
  const int n = 24;
  std::vector<double> params = RandomValues(grid.param_count(), -1, 1, 11);
  const std::vector<double> pos = RandomValues(3 * n, 0, 1, 12);
  const std::vector<double> w = RandomValues(static_cast<std::size_t>(n) * grid.output_dim(), -1, 1, 13);
  const std::vector<double> scale = RandomValues(n, 0.5, 2, 14);
  std::vector<double> grads(grid.param_count(), 0.0);
  for (int l = 0; l < grid.levels(); ++l) {
    grid.BackwardLevel(l, pos.data(), n, w.data() + l * grid.features(), grid.output_dim(), scale.data(),
                       grads.data());
  }
  // The scale multiplies each sample's gradient: the loss is sum_i scale_i * w_i . feat_i.
  auto loss = [&] {
    const auto f = Features(grid, params, pos);
    double s = 0;
    for (int i = 0; i < n; ++i) {
      for (int j = 0; j < grid.output_dim(); ++j)
        s += scale[i] * w[i * grid.output_dim() + j] * f[i * grid.output_dim() + j];
    }
    return s;
  };
  const int nonzero = ExpectGradientMatches(params.data(), grads.data(),
                                            SomeIndices(params.size(), params.size(), 1), loss, "table");
  EXPECT_GT(nonzero, 100);
}

TEST(HashGridTest, FloatAgreesWithDouble) {
  HashGridConfig c = SmallConfig();
  c.features = 4;
  const HashGrid<double> gd(c);
  const HashGrid<float> gf(c);
  const int n = 600;  // more than one tile
  const std::vector<double> pd = RandomValues(gd.param_count(), -1, 1, 31);
  const std::vector<double> xd = RandomValues(3 * n, 0, 1, 32);
  const std::vector<float> pf(pd.begin(), pd.end()), xf(xd.begin(), xd.end());
  std::vector<float> ff(static_cast<std::size_t>(n) * gf.output_dim());
  gf.ForwardRows(pf.data(), xf.data(), n, ff.data(), gf.output_dim());
  const auto fd = Features(gd, pd, std::vector<double>(xf.begin(), xf.end()));
  for (std::size_t i = 0; i < fd.size(); ++i) EXPECT_NEAR(ff[i], fd[i], 1e-5) << i;
}

// The position gradient comes out of the table scatter's pass (BackwardLevel with params and dpos).
TEST(HashGridTest, PositionGradientMatchesFiniteDifferences) {
  const HashGrid<double> grid(SmallConfig());
  const int n = 16;
  const std::vector<double> params = RandomValues(grid.param_count(), -1, 1, 41);
  std::vector<double> pos = RandomValues(3 * n, 0.02, 0.98, 42);
  const std::vector<double> w = RandomValues(static_cast<std::size_t>(n) * grid.output_dim(), -1, 1, 43);
  const std::vector<double> scale = RandomValues(n, 0.5, 2, 44);
  std::vector<double> grads(grid.param_count(), 0.0), dpos(3 * n, 0.0);
  for (int l = 0; l < grid.levels(); ++l) {
    grid.BackwardLevel(l, pos.data(), n, w.data() + l * grid.features(), grid.output_dim(), scale.data(),
                       grads.data(), params.data(), dpos.data());
  }
  auto loss = [&] {
    const auto f = Features(grid, params, pos);
    double s = 0;
    for (std::size_t j = 0; j < f.size(); ++j) s += scale[j / grid.output_dim()] * w[j] * f[j];
    return s;
  };
  EXPECT_EQ(
      ExpectGradientMatches(pos.data(), dpos.data(), SomeIndices(pos.size(), pos.size(), 3), loss, "pos"),
      3 * n);
}

// The float, 2-feature path has vector kernels (16 samples at a time, the rest one by one); it must
// agree with the portable double kernels for forward, table gradient and position gradient,
// including clamped and non-finite positions and a ragged tail.
TEST(HashGridTest, TwoFeatureFloatPathAgreesWithDouble) {
  HashGridConfig c = SmallConfig();
  c.levels = 4;
  const HashGrid<double> gd(c);
  const HashGrid<float> gf(c);
  const int n = 613, width = gd.output_dim();
  const std::vector<double> pd = RandomValues(gd.param_count(), -1, 1, 51);
  std::vector<double> xd = RandomValues(3 * n, -0.1, 1.1, 52);
  xd[5] = std::numeric_limits<double>::quiet_NaN();
  xd[40] = std::numeric_limits<double>::infinity();
  xd[41] = -std::numeric_limits<double>::infinity();
  const std::vector<double> wd = RandomValues(static_cast<std::size_t>(n) * width, -1, 1, 53);
  const std::vector<double> sd = RandomValues(n, 0.5, 2, 54);
  const std::vector<float> pf(pd.begin(), pd.end()), xf(xd.begin(), xd.end()), wf(wd.begin(), wd.end()),
      sf(sd.begin(), sd.end());
  const std::vector<double> xr(xf.begin(), xf.end());  // the positions as float sees them

  std::vector<float> ff(static_cast<std::size_t>(n) * width);
  gf.ForwardRows(pf.data(), xf.data(), n, ff.data(), width);
  const auto fd = Features(gd, pd, xr);
  for (std::size_t i = 0; i < fd.size(); ++i) ASSERT_NEAR(ff[i], fd[i], 1e-5) << i;

  std::vector<double> gdd(gd.param_count(), 0.0), dpd(3 * n, 0.0);
  std::vector<float> gff(gf.param_count(), 0.0f), dpf(3 * n, 0.0f);
  for (int l = 0; l < gd.levels(); ++l) {
    gd.BackwardLevel(l, xr.data(), n, wd.data() + 2 * l, width, sd.data(), gdd.data(), pd.data(), dpd.data());
    gf.BackwardLevel(l, xf.data(), n, wf.data() + 2 * l, width, sf.data(), gff.data(), pf.data(), dpf.data());
  }
  for (std::size_t i = 0; i < gdd.size(); ++i)
    ASSERT_NEAR(gff[i], gdd[i], 1e-4 * std::fmax(1.0, std::fabs(gdd[i]))) << i;
  for (std::size_t i = 0; i < dpd.size(); ++i)
    ASSERT_NEAR(dpf[i], dpd[i], 1e-3 * std::fmax(1.0, std::fabs(dpd[i]))) << i;
  EXPECT_EQ(dpf[5], 0.0f);   // NaN coordinate: clamped, no gradient
  EXPECT_EQ(dpf[40], 0.0f);  // +Inf
}

}  // namespace
}  // namespace endorecon::field
