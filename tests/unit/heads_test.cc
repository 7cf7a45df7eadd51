#include "worker/engine/field/heads.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "common/error.h"
#include "tests/unit/gradient_check.h"
#include "worker/engine/field/heads_math.h"
#include "worker/engine/field/sh_encoding.h"

namespace endorecon::field {
namespace {

using testing::Dot;
using testing::ExpectGradientMatches;
using testing::RandomValues;
using testing::SomeIndices;

HeadsConfig SmallConfig() {
  HeadsConfig c;
  c.density_hidden = {6};
  c.color_hidden = {5, 4};
  c.geo_features = 3;
  c.dropout = 0.25;
  return c;
}

std::vector<double> UnitDirections(int n, std::uint64_t seed) {
  std::vector<double> d = RandomValues(3 * static_cast<std::size_t>(n), -1, 1, seed);
  for (int i = 0; i < n; ++i) {
    const double len =
        std::sqrt(d[3 * i] * d[3 * i] + d[3 * i + 1] * d[3 * i + 1] + d[3 * i + 2] * d[3 * i + 2]);
    for (int a = 0; a < 3; ++a) d[3 * i + a] /= len;
  }
  return d;
}

struct DensityRun {
  std::vector<double> hidden, raw, sigma, logvar;
};

DensityRun RunDensity(DensityHead<double>& head, const std::vector<double>& params,
                      const std::vector<double>& feat, int n, const DropoutPass& drop) {
  DensityRun r;
  r.hidden.resize(static_cast<std::size_t>(n) * head.mlp().hidden_dim(0));
  r.raw.resize(static_cast<std::size_t>(n) * head.raw_dim());
  r.sigma.resize(n);
  r.logvar.resize(n);
  double* const hidden[] = {r.hidden.data()};
  head.Forward(params.data(), {n, feat.data()}, {hidden, r.raw.data(), r.sigma.data(), r.logvar.data()},
               drop);
  return r;
}

TEST(HeadsTest, DensityOutputsFollowTheirActivations) {
  DensityHead<double> head(4, SmallConfig());
  EXPECT_EQ(head.raw_dim(), 5);
  std::vector<double> params = RandomValues(head.param_count(), -1, 1, 1);
  const auto r = RunDensity(head, params, RandomValues(40, -1, 1, 2), 10, {});
  for (int i = 0; i < 10; ++i) {
    EXPECT_DOUBLE_EQ(r.sigma[i], std::exp(r.raw[i * 5]));
    EXPECT_DOUBLE_EQ(r.logvar[i], r.raw[i * 5 + 1]);
  }
}

TEST(HeadsTest, DensityGradientsMatchFiniteDifferences) {
  DensityHead<double> head(4, SmallConfig());
  const int n = 9, geo = 3;
  std::vector<double> params = RandomValues(head.param_count(), -0.8, 0.8, 3);
  std::vector<double> feat = RandomValues(4 * n, -1, 1, 4);
  const std::vector<double> ws = RandomValues(n, -1, 1, 5), wl = RandomValues(n, -1, 1, 6);
  const std::vector<double> wg = RandomValues(static_cast<std::size_t>(n) * geo, -1, 1, 7);
  const DropoutPass drop{true, 99, 3};
  auto loss = [&] {
    const auto r = RunDensity(head, params, feat, n, drop);
    double s = Dot(ws, r.sigma) + Dot(wl, r.logvar);
    for (int i = 0; i < n; ++i) {
      for (int j = 0; j < geo; ++j) s += wg[i * geo + j] * r.raw[i * head.raw_dim() + 2 + j];
    }
    return s;
  };
  auto r = RunDensity(head, params, feat, n, drop);
  double* const hidden[] = {r.hidden.data()};
  std::vector<double> grads(params.size(), 0.0), dfeat(feat.size(), 0.0);
  head.Backward(params.data(), {n, feat.data()}, {hidden, r.raw.data(), r.sigma.data(), r.logvar.data()},
                {ws.data(), wl.data(), wg.data()}, grads.data(), {dfeat.data()}, drop);
  EXPECT_GT(ExpectGradientMatches(params.data(), grads.data(), SomeIndices(params.size(), params.size(), 1),
                                  loss, "params"),
            30);
  EXPECT_GT(ExpectGradientMatches(feat.data(), dfeat.data(), SomeIndices(feat.size(), feat.size(), 2), loss,
                                  "feat"),
            20);
}

struct ColorRun {
  std::vector<double> in, h0, h1, raw, rgb, logvar;
};

ColorRun RunColor(ColorHead<double>& head, const std::vector<double>& params, const std::vector<double>& geo,
                  const std::vector<double>& dir, int n, const DropoutPass& drop,
                  const std::vector<double>& time = {}) {
  ColorRun r;
  r.in.resize(static_cast<std::size_t>(n) * head.in_dim());
  r.h0.resize(static_cast<std::size_t>(n) * 5);
  r.h1.resize(static_cast<std::size_t>(n) * 4);
  r.raw.resize(4 * static_cast<std::size_t>(n));
  r.rgb.resize(3 * static_cast<std::size_t>(n));
  r.logvar.resize(n);
  double* const hidden[2] = {r.h0.data(), r.h1.data()};
  head.Forward(params.data(), {n, geo.data(), 3, dir.data(), time.empty() ? nullptr : time.data()},
               {r.in.data(), hidden, r.raw.data(), r.rgb.data(), r.logvar.data()}, drop);
  return r;
}

TEST(HeadsTest, ColorIsInTheUnitIntervalAndSeesTheDirection) {
  ColorHead<double> head(SmallConfig());
  EXPECT_EQ(head.in_dim(), 3 + kShDims);
  const std::vector<double> params = RandomValues(head.param_count(), -0.5, 0.5, 8);
  const int n = 20;
  const std::vector<double> geo(3 * n, 0.1);
  const auto r = RunColor(head, params, geo, UnitDirections(n, 9), n, {});
  for (double c : r.rgb) {
    EXPECT_GT(c, 0.0);
    EXPECT_LT(c, 1.0);
  }
  EXPECT_NE(r.rgb[0], r.rgb[3]);  // same geometry, other direction
}

TEST(HeadsTest, TheColourHeadTakesItsOwnDropoutRateWhenOneIsGiven) {
  HeadsConfig config = SmallConfig();
  EXPECT_DOUBLE_EQ(ColorHead<double>(config).mlp().dropout_rate(), 0.25);
  config.color_dropout = 0.5;
  EXPECT_DOUBLE_EQ(ColorHead<double>(config).mlp().dropout_rate(), 0.5);
  EXPECT_DOUBLE_EQ(DensityHead<double>(4, config).mlp().dropout_rate(), 0.25);
  config.color_dropout = 1.0;
  EXPECT_THROW(ColorHead<double>{config}, Error);
}

TEST(HeadsTest, TheColourSeesTheTimeThroughSinesAndCosinesOfDoublingFrequency) {
  HeadsConfig config = SmallConfig();
  config.color_time_frequencies = 3;
  ColorHead<double> head(config);
  EXPECT_EQ(head.in_dim(), 3 + kShDims + 6);
  const std::vector<double> params = RandomValues(head.param_count(), -0.5, 0.5, 15);
  const int n = 2;
  const std::vector<double> geo(3 * n, 0.1), dir = {0, 0, 1, 0, 0, 1}, time = {0.25, 0.75};
  const auto r = RunColor(head, params, geo, dir, n, {}, time);
  const double kPi = 3.14159265358979323846;
  for (int i = 0; i < n; ++i) {
    const double* features = r.in.data() + i * head.in_dim() + 3 + kShDims;
    for (int k = 0; k < 3; ++k) {
      EXPECT_NEAR(features[2 * k], std::sin(std::ldexp(kPi, k) * time[i]), 1e-14) << i << " " << k;
      EXPECT_NEAR(features[2 * k + 1], std::cos(std::ldexp(kPi, k) * time[i]), 1e-14) << i << " " << k;
    }
  }
  EXPECT_NE(r.rgb[0], r.rgb[3]);  // same geometry and direction, another time
  config.color_time_frequencies = kMaxTimeFrequencies + 1;
  EXPECT_THROW(ColorHead<double>{config}, Error);
  config.color_time_frequencies = -1;
  EXPECT_THROW(ColorHead<double>{config}, Error);
}

// In float, as training runs: the double-angle recursion keeps every frequency's features within
// 3e-5 of sin/cos(2^k pi t) taken in double, at every time of [0, 1].
TEST(HeadsTest, TheTimeFeaturesStayAccurateInFloatAtEveryFrequency) {
  const float geo[1] = {0}, dir[3] = {0, 0, 1};
  float row[1 + kShDims + 2 * kMaxTimeFrequencies];
  double worst = 0;
  for (int i = 0; i <= 4096; ++i) {
    const float t = float(i) / 4096.0f;
    ColorInput(geo, 1, dir, t, kMaxTimeFrequencies, row);
    for (int k = 0; k < kMaxTimeFrequencies; ++k) {
      const double angle = std::ldexp(3.14159265358979323846, k) * double(t);
      worst = std::max({worst, std::fabs(row[1 + kShDims + 2 * k] - std::sin(angle)),
                        std::fabs(row[1 + kShDims + 2 * k + 1] - std::cos(angle))});
    }
  }
  EXPECT_LT(worst, 3e-5);
}

TEST(HeadsTest, ColorGradientsMatchFiniteDifferences) {
  HeadsConfig config = SmallConfig();
  config.color_time_frequencies = 2;
  ColorHead<double> head(config);
  const int n = 8;
  std::vector<double> params = RandomValues(head.param_count(), -0.8, 0.8, 10);
  std::vector<double> geo = RandomValues(3 * n, -1, 1, 11);
  const std::vector<double> dir = UnitDirections(n, 12);
  const std::vector<double> wc = RandomValues(3 * n, -1, 1, 13), wl = RandomValues(n, -1, 1, 14);
  const std::vector<double> time = RandomValues(n, 0, 1, 16);
  const DropoutPass drop{true, 5, 0};
  auto loss = [&] {
    const auto r = RunColor(head, params, geo, dir, n, drop, time);
    return Dot(wc, r.rgb) + Dot(wl, r.logvar);
  };
  auto r = RunColor(head, params, geo, dir, n, drop, time);
  double* const hidden[2] = {r.h0.data(), r.h1.data()};
  std::vector<double> grads(params.size(), 0.0), dgeo(geo.size(), 0.0);
  head.Backward(params.data(), {n, geo.data(), 3, dir.data(), time.data()},
                {r.in.data(), hidden, r.raw.data(), r.rgb.data(), r.logvar.data()}, {wc.data(), wl.data()},
                grads.data(), {dgeo.data()}, drop);
  EXPECT_GT(ExpectGradientMatches(params.data(), grads.data(), SomeIndices(params.size(), params.size(), 1),
                                  loss, "params"),
            40);
  EXPECT_GT(
      ExpectGradientMatches(geo.data(), dgeo.data(), SomeIndices(geo.size(), geo.size(), 2), loss, "geo"),
      10);
}

}  // namespace
}  // namespace endorecon::field
