// The whole field at extreme coordinates (issue 6 §1): hash-grid positions at exactly 0 and 1,
// outside the unit cube, NaN and +-Inf are clamped (never a wild read): outputs are finite and equal
// those of the clamped position, and the backward pass stays finite. And the float32 field against a
// float64 evaluation of the same parameters and inputs, with the tolerance stated.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <random>
#include <vector>

#include "worker/engine/field/field.h"

namespace endorecon::field {
namespace {

constexpr float kNan = std::numeric_limits<float>::quiet_NaN();
constexpr float kInf = std::numeric_limits<float>::infinity();

// Small but complete: two grids with hashed and dense levels, deformation, both heads.
FieldConfig SmallConfig(bool deformation) {
  FieldConfig c;
  c.grids.base_resolutions = {4, 6};
  c.grids.scales = {2.0, 1.5};
  c.grids.levels = 4;
  c.grids.features = 2;
  c.grids.log2_table = 8;
  c.blend_hidden = 4;
  c.deformation.enabled = deformation;
  c.deformation.resolution = 4;
  c.deformation.time_knots = 3;
  c.heads.density_hidden = {16};
  c.heads.color_hidden = {16, 16};
  c.heads.geo_features = 7;
  return c;
}

// Every parameter random (the deformation and the blend's output layer start at zero otherwise).
template <typename S>
void Randomise(FieldT<S>& field, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  for (auto& block : field.Blocks()) {
    const double scale = block.name == "deform" ? 0.05 : block.name == "grid" ? 0.5 : 0.6;
    std::uniform_real_distribution<double> u(-scale, scale);
    for (std::size_t i = 0; i < block.size; ++i) block.value[i] = static_cast<S>(static_cast<float>(u(rng)));
  }
}

template <typename S>
struct Outputs {
  explicit Outputs(int n) : sigma(n), sigma_logvar(n), rgb(3 * std::size_t(n)), rgb_logvar(n) {}
  FieldOutputT<S> view() { return {sigma.data(), sigma_logvar.data(), rgb.data(), rgb_logvar.data()}; }
  std::vector<S> sigma, sigma_logvar, rgb, rgb_logvar;
};

// Runs positions through Forward (no dropout) at one time, every view direction +z.
template <typename S>
Outputs<S> Evaluate(FieldT<S>& field, const std::vector<S>& pos, S time) {
  const int n = static_cast<int>(pos.size() / 3);
  const std::vector<S> times(n, time);
  std::vector<S> dir(3 * std::size_t(n), S(0));
  for (int i = 0; i < n; ++i) dir[3 * i + 2] = S(1);
  Outputs<S> out(n);
  auto view = out.view();
  field.Forward({n, pos.data(), times.data(), dir.data()}, view, false, 0);
  return out;
}

// Coordinates a ray sampler can produce at the box's faces or beyond, and ones it must never read by.
const float kWild[] = {0.0f, 1.0f,   -0.0f, -1e-7f, 1.0f + 1e-7f, -3.0f,
                       2.5f, -1e30f, 1e30f, kNan,   kInf,         -kInf};

float Clamped(float x) {
  if (std::isnan(x) || x < 0) return 0.0f;
  return x > 1 ? 1.0f : x;
}

// Positions with one wild coordinate on each axis in turn, the other two ordinary.
std::vector<float> WildPositions(std::vector<float>* clamped) {
  std::vector<float> pos;
  for (float w : kWild) {
    for (int axis = 0; axis < 3; ++axis) {
      float p[3] = {0.3f, 0.6f, 0.45f};
      p[axis] = w;
      pos.insert(pos.end(), p, p + 3);
      p[axis] = Clamped(w);
      clamped->insert(clamped->end(), p, p + 3);
    }
  }
  // All three wild at once.
  for (float w : kWild) {
    pos.insert(pos.end(), {w, w, w});
    clamped->insert(clamped->end(), {Clamped(w), Clamped(w), Clamped(w)});
  }
  return pos;
}

void ExpectFiniteAndValid(const Outputs<float>& out, const char* what) {
  for (std::size_t i = 0; i < out.sigma.size(); ++i) {
    EXPECT_TRUE(std::isfinite(out.sigma[i]) && out.sigma[i] >= 0)
        << what << " sample " << i << ": " << out.sigma[i];
    EXPECT_TRUE(std::isfinite(out.sigma_logvar[i])) << what << " sample " << i;
    EXPECT_TRUE(std::isfinite(out.rgb_logvar[i])) << what << " sample " << i;
    for (int c = 0; c < 3; ++c) {
      EXPECT_TRUE(out.rgb[3 * i + c] >= 0 && out.rgb[3 * i + c] <= 1) << what << " sample " << i;
    }
  }
}

// Static scene and, with deformation, t = 0 (where dx is exactly 0): x0 = x, so a wild coordinate
// must read exactly what its clamped value reads. Bit-equal: the clamp happens before any arithmetic.
TEST(FieldExtremes, WildCoordinatesReadTheClampedPosition) {
  for (bool deformation : {false, true}) {
    FieldT<float> field(SmallConfig(deformation), 3);
    Randomise(field, 17);
    std::vector<float> clamped;
    const std::vector<float> wild = WildPositions(&clamped);
    const Outputs<float> a = Evaluate(field, wild, 0.0f), b = Evaluate(field, clamped, 0.0f);
    ExpectFiniteAndValid(a, deformation ? "deformed, t = 0" : "static");
    EXPECT_EQ(a.sigma, b.sigma) << "deformation " << deformation;
    EXPECT_EQ(a.sigma_logvar, b.sigma_logvar);
    EXPECT_EQ(a.rgb, b.rgb);
    EXPECT_EQ(a.rgb_logvar, b.rgb_logvar);
  }
}

// At t != 0 the deformed position x0 = x + dx(clamp(x), t) is what the grids clamp, so outputs of
// wild inputs are only required to be finite and in range; and the gradients of every parameter
// group must be finite too (the clamp stops the position gradient, it must not make a NaN).
TEST(FieldExtremes, WildCoordinatesKeepForwardAndBackwardFinite) {
  FieldT<float> field(SmallConfig(true), 5);
  Randomise(field, 23);
  std::vector<float> clamped;
  const std::vector<float> pos = WildPositions(&clamped);
  const int n = static_cast<int>(pos.size() / 3);
  for (float t : {0.0f, 0.37f, 1.0f}) {
    const std::vector<float> times(n, t);
    std::vector<float> dir(3 * std::size_t(n), 0.0f);
    for (int i = 0; i < n; ++i) dir[3 * i] = 1.0f;
    Outputs<float> out(n);
    auto view = out.view();
    const SampleBatch batch{n, pos.data(), times.data(), dir.data()};
    field.Forward(batch, view, true, 9);
    ExpectFiniteAndValid(out, "deformed");
    const std::vector<float> ones(3 * std::size_t(n), 1.0f);
    field.ZeroGrad();
    field.Backward(batch, {ones.data(), ones.data(), ones.data(), ones.data()});
    for (const auto& block : field.Blocks()) {
      for (std::size_t i = 0; i < block.size; ++i) {
        ASSERT_TRUE(std::isfinite(block.grad[i]))
            << "t = " << t << ", group " << block.name << " [" << i << "]";
      }
    }
  }
}

// The float32 field against FieldT<double> holding the same (float-representable) parameters, on
// ordinary and boundary positions at several times. Tolerance: 1e-5 relative to max(1, |value|) on
// every output. A sample passes ~2 grids x 4 levels x 8 corners of interpolation, the blend and three
// layers of 16-wide matrix products with exp/softplus/sigmoid activations, each adding a few float
// ulps (6e-8); the worst case observed is 3.2e-7 (recorded as the test's worst_relative_error).
TEST(FieldExtremes, FloatMatchesDoubleWithinStatedTolerance) {
  FieldT<float> single(SmallConfig(true), 8);
  FieldT<double> twice(SmallConfig(true), 8);
  Randomise(single, 31);
  auto fb = single.Blocks();
  auto db = twice.Blocks();
  ASSERT_EQ(fb.size(), db.size());
  for (std::size_t k = 0; k < fb.size(); ++k) {
    ASSERT_EQ(fb[k].name, db[k].name);
    ASSERT_EQ(fb[k].size, db[k].size);
    for (std::size_t i = 0; i < fb[k].size; ++i) db[k].value[i] = fb[k].value[i];
  }
  std::mt19937_64 rng(4);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  std::vector<float> pos;
  for (int i = 0; i < 600; ++i) pos.push_back(u(rng));
  for (float a : {0.0f, 1.0f}) {
    for (float b : {0.0f, 0.5f, 1.0f}) pos.insert(pos.end(), {a, b, 1.0f - a});
  }
  const std::vector<double> pos_d(pos.begin(), pos.end());
  double worst = 0;
  for (float t : {0.0f, 0.25f, 0.8f}) {
    const Outputs<float> f = Evaluate(single, pos, t);
    const Outputs<double> d = Evaluate(twice, pos_d, double(t));
    const auto compare = [&](const std::vector<float>& a, const std::vector<double>& b, const char* what) {
      for (std::size_t i = 0; i < a.size(); ++i) {
        const double err = std::fabs(double(a[i]) - b[i]) / std::max(1.0, std::fabs(b[i]));
        worst = std::max(worst, err);
        ASSERT_LE(err, 1e-5) << what << " [" << i << "] at t = " << t << ": " << a[i] << " vs " << b[i];
      }
    };
    compare(f.sigma, d.sigma, "sigma");
    compare(f.sigma_logvar, d.sigma_logvar, "sigma_logvar");
    compare(f.rgb, d.rgb, "rgb");
    compare(f.rgb_logvar, d.rgb_logvar, "rgb_logvar");
  }
  char text[32];
  std::snprintf(text, sizeof(text), "%.3g", worst);
  RecordProperty("worst_relative_error", text);
}

}  // namespace
}  // namespace endorecon::field
