// Volume rendering under extreme densities and intervals (issue 6 §1): outputs and gradients stay
// finite, match closed forms where they exist, and float32 agrees with a float64 evaluation of the
// same (float-representable) inputs to the tolerances stated in each test.
#include <gtest/gtest.h>

#include <cfloat>
#include <cmath>
#include <random>
#include <vector>

#include "worker/engine/render/stratified_sampler.h"
#include "worker/engine/render/volume_renderer.h"

namespace endorecon::render {
namespace {

struct RayInput {
  std::vector<float> sigma, rgb, s, delta;
  int n() const { return static_cast<int>(sigma.size()); }
};

// Forward and backward results of one precision, widened to double for comparison.
struct RayOutput {
  double rgb[3], depth, opacity, transmittance;
  int samples_used;
  std::vector<double> weights, d_sigma, d_rgb;
};

// The loss gradients used throughout: every output and every weight matters.
constexpr double kGradRgb[3] = {0.5, -1.0, 0.25};
constexpr double kGradDepth = 0.3, kGradOpacity = -0.7, kGradWeight = 0.2;

template <typename S>
RayOutput Evaluate(const RayInput& in, double min_transmittance = 0) {
  const int n = in.n();
  std::vector<S> sigma(in.sigma.begin(), in.sigma.end()), rgb(in.rgb.begin(), in.rgb.end()),
      s(in.s.begin(), in.s.end()), delta(in.delta.begin(), in.delta.end()), w(n), d_w(n, S(kGradWeight)),
      d_sigma(n, S(0)), d_rgb(3 * n, S(0));
  const RayComposite<S> out = CompositeRay(sigma.data(), rgb.data(), s.data(), delta.data(), n, w.data(),
                                           static_cast<S>(min_transmittance));
  RayCompositeGrad<S> grad;
  for (int c = 0; c < 3; ++c) grad.rgb[c] = static_cast<S>(kGradRgb[c]);
  grad.depth = static_cast<S>(kGradDepth);
  grad.opacity = static_cast<S>(kGradOpacity);
  CompositeRayBackward(sigma.data(), rgb.data(), s.data(), delta.data(), w.data(), out, grad, d_w.data(),
                       d_sigma.data(), d_rgb.data());
  RayOutput r{{out.rgb[0], out.rgb[1], out.rgb[2]},
              out.depth,
              out.opacity,
              out.transmittance,
              out.samples_used,
              std::vector<double>(w.begin(), w.end()),
              std::vector<double>(d_sigma.begin(), d_sigma.end()),
              std::vector<double>(d_rgb.begin(), d_rgb.end())};
  return r;
}

RayInput ConstantRay(int n, float sigma, float delta) {
  RayInput in{std::vector<float>(n, sigma), std::vector<float>(3 * n), std::vector<float>(n),
              std::vector<float>(n, delta)};
  for (int j = 0; j < n; ++j) {
    in.s[j] = 1.0f + static_cast<float>(j);
    for (int c = 0; c < 3; ++c) in.rgb[3 * j + c] = 0.25f * static_cast<float>(c + 1);
  }
  return in;
}

void ExpectFinite(const RayOutput& out, const char* what) {
  for (double v : out.rgb) EXPECT_TRUE(std::isfinite(v)) << what;
  EXPECT_TRUE(std::isfinite(out.depth)) << what;
  EXPECT_GE(out.opacity, 0.0) << what;
  EXPECT_LE(out.opacity, 1.0 + 1e-6) << what;
  EXPECT_GE(out.transmittance, 0.0) << what;
  EXPECT_LE(out.transmittance, 1.0) << what;
  for (double v : out.weights) {
    EXPECT_GE(v, 0.0) << what;
    EXPECT_LE(v, 1.0) << what;
  }
  for (double v : out.d_sigma) EXPECT_TRUE(std::isfinite(v)) << what;
  for (double v : out.d_rgb) EXPECT_TRUE(std::isfinite(v)) << what;
}

double MaxAbs(const std::vector<double>& v) {
  double m = 0;
  for (double x : v) m = std::fmax(m, std::fabs(x));
  return m;
}

// Float against double on the same inputs. Tolerances: colour, opacity and transmittance 2e-6
// absolute (a few float ulps of values in [0, 1]); depth 2e-6 relative to the farthest sample;
// gradients 1e-4 relative to the largest gradient of the ray (they are sums of terms of either sign).
void ExpectFloatMatchesDouble(const RayInput& in, const char* what) {
  const RayOutput f = Evaluate<float>(in), d = Evaluate<double>(in);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(f.rgb[c], d.rgb[c], 2e-6) << what;
  EXPECT_NEAR(f.opacity, d.opacity, 2e-6) << what;
  EXPECT_NEAR(f.transmittance, d.transmittance, 2e-6) << what;
  EXPECT_NEAR(f.depth, d.depth, 2e-6 * in.s.back()) << what;
  const double sigma_scale = std::fmax(MaxAbs(d.d_sigma), 1e-30),
               rgb_scale = std::fmax(MaxAbs(d.d_rgb), 1e-30);
  for (int j = 0; j < in.n(); ++j) {
    EXPECT_NEAR(f.d_sigma[j], d.d_sigma[j], 1e-4 * sigma_scale) << what << " sample " << j;
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(f.d_rgb[3 * j + c], d.d_rgb[3 * j + c], 1e-4 * rgb_scale) << what;
  }
}

TEST(VolumeRenderingExtremes, EveryDensityAndIntervalStaysFinite) {
  const float densities[] = {0.0f, 1e-12f, 1e-3f, 1.0f, 1e3f, 1e6f, 1e8f, FLT_MAX};
  const float intervals[] = {0.0f, 1e-9f, 1e-3f, 1.0f, 1e10f, 1e30f, INFINITY};
  for (float sigma : densities) {
    for (float delta : intervals) {
      const RayInput in = ConstantRay(8, sigma, delta);
      const std::string what = "sigma=" + std::to_string(sigma) + " delta=" + std::to_string(delta);
      ExpectFinite(Evaluate<float>(in), what.c_str());
      ExpectFinite(Evaluate<double>(in), what.c_str());
      ExpectFloatMatchesDouble(in, what.c_str());
    }
  }
}

TEST(VolumeRenderingExtremes, TinyOpticalDepthKeepsItsRelativeAccuracy) {
  // sigma delta = 1e-21 per sample: alpha = -expm1(-1e-21) = 1e-21 to float precision, where
  // 1 - exp(-tau) would give exactly 0.
  const RayInput in = ConstantRay(8, 1e-12f, 1e-9f);
  const RayOutput f = Evaluate<float>(in);
  const double tau = static_cast<double>(1e-12f) * static_cast<double>(1e-9f);
  EXPECT_NEAR(f.opacity, 8 * tau, 8 * tau * 1e-5);
  EXPECT_NEAR(f.weights[0], tau, tau * 1e-6);
}

TEST(VolumeRenderingExtremes, RayThatHitsNothing) {
  for (float delta : {0.0f, 1e-9f, 0.5f, 1e30f, INFINITY}) {
    const RayInput in = ConstantRay(16, 0.0f, delta);
    const RayOutput f = Evaluate<float>(in);
    ExpectFinite(f, "empty");
    EXPECT_EQ(f.opacity, 0.0);
    EXPECT_EQ(f.depth, 0.0);
    EXPECT_EQ(f.transmittance, 1.0);
    for (double c : f.rgb) EXPECT_EQ(c, 0.0);
  }
}

TEST(VolumeRenderingExtremes, RayStartingInsideAnOpaqueMedium) {
  // The first sample is already inside tissue of density 1e8: all weight on it, depth = s_0.
  for (float sigma : {1e4f, 1e6f, 1e8f}) {
    RayInput in = ConstantRay(32, sigma, 0.0625f);
    in.rgb[0] = 0.9f;
    const RayOutput f = Evaluate<float>(in), d = Evaluate<double>(in);
    ExpectFinite(f, "opaque");
    EXPECT_NEAR(f.weights[0], 1.0, 1e-7);
    EXPECT_NEAR(f.depth, in.s[0], 1e-6);
    EXPECT_NEAR(f.rgb[0], 0.9, 1e-7);
    EXPECT_EQ(f.transmittance, 0.0);
    for (int j = 1; j < in.n(); ++j) EXPECT_EQ(f.d_sigma[j], 0.0);  // nothing behind can be seen
    EXPECT_NEAR(f.d_sigma[0], d.d_sigma[0], 1e-6 + 1e-4 * std::fabs(d.d_sigma[0]));
  }
}

TEST(VolumeRenderingExtremes, StiffSurfaceTerminatesEarlyAfterOneSample) {
  // Alpha reaches 1 within one sample: with early termination at T < 1e-4 the ray stops right
  // after the surface and renders the same as without it.
  RayInput in = ConstantRay(64, 0.0f, 0.01f);
  for (int j = 20; j < 64; ++j) in.sigma[j] = 1e5f;
  const RayOutput early = Evaluate<float>(in, 1e-4), full = Evaluate<float>(in);
  EXPECT_EQ(early.samples_used, 21);
  EXPECT_NEAR(early.depth, full.depth, 1e-6 * in.s.back());
  EXPECT_NEAR(early.opacity, 1.0, 1e-6);
  ExpectFinite(early, "stiff");
}

TEST(VolumeRenderingExtremes, RealisticRaysAgreeInFloatAndDouble) {
  std::mt19937 gen(17);
  std::uniform_real_distribution<float> log_sigma(-3.0f, 4.0f), color(0.0f, 1.0f), jitter(0.0f, 1.0f);
  for (int ray = 0; ray < 300; ++ray) {
    RayInput in{std::vector<float>(64), std::vector<float>(192), std::vector<float>(64),
                std::vector<float>(64)};
    StratifiedSamples(
        2.0f, 6.0f, 64, [&](unsigned) { return jitter(gen); }, in.s.data(), in.delta.data());
    for (int j = 0; j < 64; ++j) {
      in.sigma[j] = std::pow(10.0f, log_sigma(gen));
      for (int c = 0; c < 3; ++c) in.rgb[3 * j + c] = color(gen);
    }
    ExpectFloatMatchesDouble(in, "random ray");
  }
}

}  // namespace
}  // namespace endorecon::render
