#include "worker/engine/render/volume_renderer.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "tests/unit/central_difference.h"
#include "worker/engine/render/stratified_sampler.h"

namespace endorecon::render {
namespace {

using testing::CentralDifference;
using testing::CloseRelative;

struct Ray {
  std::vector<double> sigma, rgb, s, delta;
  int n() const { return static_cast<int>(sigma.size()); }
};

// n samples at bin centres (u = 0.5) of [near, far], all with density `sigma` and colour `color`.
Ray UniformRay(int n, double near, double far, double sigma, const double* color, double jitter = 0.5) {
  Ray ray{std::vector<double>(n, sigma), std::vector<double>(3 * n), std::vector<double>(n),
          std::vector<double>(n)};
  StratifiedSamples(
      near, far, n, [jitter](unsigned) { return jitter; }, ray.s.data(), ray.delta.data());
  for (int j = 0; j < n; ++j) {
    for (int c = 0; c < 3; ++c) ray.rgb[3 * j + c] = color[c];
  }
  return ray;
}

Ray RandomRay(int n, unsigned seed) {
  std::mt19937 gen(seed);
  std::uniform_real_distribution<double> density(0.05, 8.0), color(0.0, 1.0), jitter(0.0, 1.0);
  Ray ray{std::vector<double>(n), std::vector<double>(3 * n), std::vector<double>(n), std::vector<double>(n)};
  StratifiedSamples(
      2.0, 6.0, n, [&](unsigned) { return jitter(gen); }, ray.s.data(), ray.delta.data());
  for (int j = 0; j < n; ++j) {
    ray.sigma[j] = density(gen);
    for (int c = 0; c < 3; ++c) ray.rgb[3 * j + c] = color(gen);
  }
  return ray;
}

RayComposite<double> Render(const Ray& ray, std::vector<double>& weights, double min_transmittance = 0) {
  weights.assign(ray.n(), -1.0);
  return CompositeRay(ray.sigma.data(), ray.rgb.data(), ray.s.data(), ray.delta.data(), ray.n(),
                      weights.data(), min_transmittance);
}

// The backward pass's d_sigma and d_rgb against central differences of `loss` in every density and
// colour of the ray.
template <typename Loss>
void ExpectCentralDifferences(Ray& ray, const Loss& loss, const std::vector<double>& d_sigma,
                              const std::vector<double>& d_rgb) {
  for (int j = 0; j < ray.n(); ++j) {
    const double fd = CentralDifference(ray.sigma[j], 1e-6, loss);
    EXPECT_TRUE(CloseRelative(d_sigma[j], fd, 1e-7)) << "sigma " << j << ": " << d_sigma[j] << " vs " << fd;
    for (int c = 0; c < 3; ++c) {
      const double fd_c = CentralDifference(ray.rgb[3 * j + c], 1e-6, loss);
      EXPECT_TRUE(CloseRelative(d_rgb[3 * j + c], fd_c, 1e-7)) << "rgb " << j << "," << c;
    }
  }
}

TEST(VolumeRenderer, BackwardMatchesCentralDifferences) {
  Ray ray = RandomRay(16, 7);
  const int n = ray.n();
  // L = a.C + b D + e A + sum_j q_j w_j: every path of the backward pass is exercised.
  const RayCompositeGrad<double> grad{{0.3, -1.2, 0.7}, 0.45, -0.8};
  std::vector<double> q(n);
  std::mt19937 gen(3);
  std::uniform_real_distribution<double> uq(-1.0, 1.0);
  for (double& v : q) v = uq(gen);
  auto loss = [&] {
    std::vector<double> w;
    const RayComposite<double> out = Render(ray, w);
    double l = grad.depth * out.depth + grad.opacity * out.opacity;
    for (int c = 0; c < 3; ++c) l += grad.rgb[c] * out.rgb[c];
    for (int j = 0; j < n; ++j) l += q[j] * w[j];
    return l;
  };

  std::vector<double> w;
  const RayComposite<double> out = Render(ray, w);
  std::vector<double> d_sigma(n, 0.0), d_rgb(3 * n, 0.0);
  CompositeRayBackward(ray.sigma.data(), ray.rgb.data(), ray.s.data(), ray.delta.data(), w.data(), out, grad,
                       q.data(), d_sigma.data(), d_rgb.data());
  ExpectCentralDifferences(ray, loss, d_sigma, d_rgb);
}

TEST(VolumeRenderer, BackwardAddsToExistingGradients) {
  const Ray ray = RandomRay(8, 11);
  std::vector<double> w;
  const RayComposite<double> out = Render(ray, w);
  const RayCompositeGrad<double> grad{{1, 0.5, -0.25}, 0.1, 0.2};
  std::vector<double> once_sigma(8, 0.0), once_rgb(24, 0.0), twice_sigma(8, 0.0), twice_rgb(24, 0.0);
  CompositeRayBackward(ray.sigma.data(), ray.rgb.data(), ray.s.data(), ray.delta.data(), w.data(), out, grad,
                       static_cast<const double*>(nullptr), once_sigma.data(), once_rgb.data());
  for (int k = 0; k < 2; ++k) {
    CompositeRayBackward(ray.sigma.data(), ray.rgb.data(), ray.s.data(), ray.delta.data(), w.data(), out,
                         grad, static_cast<const double*>(nullptr), twice_sigma.data(), twice_rgb.data());
  }
  for (int j = 0; j < 8; ++j) {
    EXPECT_NE(once_sigma[j], 0.0);
    EXPECT_DOUBLE_EQ(twice_sigma[j], 2 * once_sigma[j]);
  }
  for (int i = 0; i < 24; ++i) EXPECT_DOUBLE_EQ(twice_rgb[i], 2 * once_rgb[i]);
}

TEST(VolumeRenderer, ConstantSlabMatchesClosedForm) {
  // A slab [0, L] of constant density sigma and colour c: C = c (1 - e^{-sigma L}) exactly (the
  // transmittance of constant density is exact for any partition), and
  // D = int_0^L s sigma e^{-sigma s} ds = (1 - e^{-sigma L} (1 + sigma L)) / sigma, which bin
  // centres reach with the midpoint rule's O(delta^2) error.
  const double sigma = 2.0, length = 1.5, color[3] = {0.2, 0.5, 0.9};
  const Ray ray = UniformRay(4000, 0.0, length, sigma, color);
  std::vector<double> w;
  const RayComposite<double> out = Render(ray, w);
  const double opacity = 1 - std::exp(-sigma * length);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(out.rgb[c], color[c] * opacity, 1e-12);
  EXPECT_NEAR(out.opacity, opacity, 1e-12);
  EXPECT_NEAR(out.transmittance, std::exp(-sigma * length), 1e-12);
  const double depth = (1 - std::exp(-sigma * length) * (1 + sigma * length)) / sigma;
  EXPECT_NEAR(out.depth, depth, 1e-6);
  EXPECT_EQ(out.samples_used, 4000);
}

TEST(VolumeRenderer, BackgroundShowsThroughWhatTheSlabLets) {
  // The constant slab in front of a background bg: C = c (1 - e^{-sigma L}) + bg e^{-sigma L}.
  const double sigma = 0.7, length = 1.5, color[3] = {0.2, 0.5, 0.9}, background[3] = {1.0, 0.25, 0.0};
  const Ray ray = UniformRay(500, 0.0, length, sigma, color);
  std::vector<double> w;
  RayComposite<double> out = Render(ray, w);
  AddBackground(out, background);
  const double through = std::exp(-sigma * length);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(out.rgb[c], color[c] * (1 - through) + background[c] * through, 1e-12);
}

TEST(VolumeRenderer, BackgroundBackwardMatchesCentralDifferences) {
  Ray ray = RandomRay(12, 5);
  for (double& sigma : ray.sigma) sigma *= 0.05;  // a thin ray: the background carries weight
  const int n = ray.n();
  const double background[3] = {0.9, 0.6, 0.3};
  const RayCompositeGrad<double> upstream{{0.3, -1.2, 0.7}, 0.45, -0.8};
  auto loss = [&] {
    std::vector<double> w;
    RayComposite<double> out = Render(ray, w);
    AddBackground(out, background);
    double l = upstream.depth * out.depth + upstream.opacity * out.opacity;
    for (int c = 0; c < 3; ++c) l += upstream.rgb[c] * out.rgb[c];
    return l;
  };
  std::vector<double> w;
  RayComposite<double> out = Render(ray, w);
  AddBackground(out, background);
  EXPECT_GT(out.transmittance, 0.2);
  RayCompositeGrad<double> grad = upstream;
  BackgroundBackward(background, grad);
  std::vector<double> d_sigma(n, 0.0), d_rgb(3 * n, 0.0);
  CompositeRayBackward(ray.sigma.data(), ray.rgb.data(), ray.s.data(), ray.delta.data(), w.data(), out, grad,
                       static_cast<const double*>(nullptr), d_sigma.data(), d_rgb.data());
  ExpectCentralDifferences(ray, loss, d_sigma, d_rgb);
}

TEST(VolumeRenderer, StepInDensityPutsDepthAtTheStep) {
  // Empty space, then an opaque medium from s0 on: all weight lands on the first opaque sample.
  const double color[3] = {0.1, 0.2, 0.3};
  Ray ray = UniformRay(64, 1.0, 5.0, 0.0, color, 0.0);  // samples at the bin starts
  const int first_opaque = 23;
  const double s0 = ray.s[first_opaque];
  for (int j = first_opaque; j < ray.n(); ++j) {
    ray.sigma[j] = 1e6;
    ray.rgb[3 * j] = 0.9;
  }
  std::vector<double> w;
  const RayComposite<double> out = Render(ray, w);
  EXPECT_NEAR(out.depth, s0, 1e-12);
  EXPECT_NEAR(out.opacity, 1.0, 1e-12);
  EXPECT_NEAR(out.rgb[0], 0.9, 1e-12);
  EXPECT_NEAR(w[first_opaque], 1.0, 1e-12);
  EXPECT_EQ(w[first_opaque - 1], 0.0);
}

TEST(VolumeRenderer, EmptyRayHasNoWeightAndDepthZero) {
  const double color[3] = {0.7, 0.7, 0.7};
  const Ray ray = UniformRay(32, 2.0, 6.0, 0.0, color);
  std::vector<double> w;
  const RayComposite<double> out = Render(ray, w);
  for (double v : w) EXPECT_EQ(v, 0.0);
  for (double v : out.rgb) EXPECT_EQ(v, 0.0);
  EXPECT_EQ(out.depth, 0.0);
  EXPECT_EQ(out.opacity, 0.0);
  EXPECT_EQ(out.transmittance, 1.0);
  // Zero density still gets a gradient (one-sided): with T = 1 and no weight behind,
  // dL/dsigma_j = delta_j dL/dw_j, here delta_j (a.c_j + b s_j + e).
  const RayCompositeGrad<double> grad{{1, 0, 0}, 0.5, 0.25};
  std::vector<double> d_sigma(32, 0.0), d_rgb(96, 0.0);
  CompositeRayBackward(ray.sigma.data(), ray.rgb.data(), ray.s.data(), ray.delta.data(), w.data(), out, grad,
                       static_cast<const double*>(nullptr), d_sigma.data(), d_rgb.data());
  for (int j = 0; j < 32; ++j) {
    EXPECT_NEAR(d_sigma[j], ray.delta[j] * (0.7 + 0.5 * ray.s[j] + 0.25), 1e-12);
    EXPECT_EQ(d_rgb[3 * j], 0.0);
  }
}

TEST(VolumeRenderer, EarlyTerminationBoundsTheTail) {
  const double color[3] = {1, 1, 1};
  Ray ray = UniformRay(128, 2.0, 6.0, 3.0, color);
  for (int j = 0; j < ray.n(); ++j) ray.rgb[3 * j + 1] = 0.5 + 0.5 * std::sin(j);
  std::vector<double> w_full, w_early;
  const RayComposite<double> full = Render(ray, w_full);
  const double min_t = 1e-4;
  const RayComposite<double> early = Render(ray, w_early, min_t);
  ASSERT_LT(early.samples_used, ray.n());
  ASSERT_GT(early.samples_used, 0);
  EXPECT_LT(early.transmittance, min_t);
  for (int j = early.samples_used; j < ray.n(); ++j) EXPECT_EQ(w_early[j], 0.0);
  for (int j = 0; j < early.samples_used; ++j) EXPECT_EQ(w_early[j], w_full[j]);
  // What the skipped tail could add is bounded by the transmittance left at the stop.
  const double tail = early.transmittance;
  EXPECT_GT(full.opacity - early.opacity, 0.0);
  EXPECT_LE(full.opacity - early.opacity, tail);
  for (int c = 0; c < 3; ++c) EXPECT_LE(std::fabs(full.rgb[c] - early.rgb[c]), tail * 1.0);
  EXPECT_LE(std::fabs(full.depth - early.depth), tail * ray.s.back());

  // The skipped samples get no gradient.
  std::vector<double> d_sigma(ray.n(), 0.0), d_rgb(3 * ray.n(), 0.0);
  CompositeRayBackward(ray.sigma.data(), ray.rgb.data(), ray.s.data(), ray.delta.data(), w_early.data(),
                       early, RayCompositeGrad<double>{{1, 1, 1}, 1, 1}, static_cast<const double*>(nullptr),
                       d_sigma.data(), d_rgb.data());
  for (int j = early.samples_used; j < ray.n(); ++j) EXPECT_EQ(d_sigma[j], 0.0);
  EXPECT_NE(d_sigma[0], 0.0);
}

TEST(VolumeRenderer, NegativeDensityCountsAsZero) {
  const double color[3] = {1, 0, 0};
  Ray ray = UniformRay(4, 0.0, 1.0, -5.0, color);
  std::vector<double> w;
  const RayComposite<double> out = Render(ray, w);
  EXPECT_EQ(out.opacity, 0.0);
  std::vector<double> d_sigma(4, 0.0), d_rgb(12, 0.0);
  CompositeRayBackward(ray.sigma.data(), ray.rgb.data(), ray.s.data(), ray.delta.data(), w.data(), out,
                       RayCompositeGrad<double>{{1, 1, 1}, 1, 1}, static_cast<const double*>(nullptr),
                       d_sigma.data(), d_rgb.data());
  for (double v : d_sigma) EXPECT_EQ(v, 0.0);
}

}  // namespace
}  // namespace endorecon::render
