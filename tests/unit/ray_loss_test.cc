// The per-ray combination of the loss terms that the CPU trainer and the CUDA loss kernel share.
#include "worker/engine/train/ray_loss.h"

#include <gtest/gtest.h>

#include <random>
#include <vector>

#include "tests/unit/central_difference.h"

namespace endorecon::train {
namespace {

using testing::CentralDifference;
using testing::CloseRelative;

constexpr int kSamples = 9;

struct Ray {
  render::RayComposite<double> composite;
  std::vector<double> weights, mean_rgb, log_var;
  double target[3] = {0.2, 0.7, 0.45};
  double prior = 2.3;
};

Ray RandomRay(unsigned seed) {
  std::mt19937 gen(seed);
  std::uniform_real_distribution<double> w(0.0, 0.2), c(0.0, 1.0), l(-5.0, 2.0);
  Ray ray{
      {}, std::vector<double>(kSamples), std::vector<double>(3 * kSamples), std::vector<double>(kSamples)};
  for (int j = 0; j < kSamples; ++j) {
    ray.weights[j] = w(gen);
    ray.log_var[j] = l(gen);
    for (int k = 0; k < 3; ++k) ray.mean_rgb[3 * j + k] = c(gen);
  }
  ray.composite.rgb[0] = 0.3;
  ray.composite.rgb[1] = 0.5;
  ray.composite.rgb[2] = 0.6;
  ray.composite.depth = 2.0;
  return ray;
}

RayLossTerms AllTerms(float huber_delta) {
  RayLossTerms terms;
  terms.rgb_l2_scale = 0.7f;
  terms.depth_scale = 0.25f;
  terms.depth_range = 4.0f;
  terms.huber_delta = huber_delta;
  terms.nll_scale = 0.03f;
  terms.variance_reg_scale = 0.02f;
  terms.variance_eps = 1e-3f;
  return terms;
}

double Loss(const Ray& ray, const RayLossTerms& terms, render::RayCompositeGrad<double>* grad = nullptr,
            double* d_mean = nullptr, double* d_lv = nullptr) {
  render::RayCompositeGrad<double> unused;
  return RayLoss(ray.composite, ray.weights.data(), ray.mean_rgb.data(), ray.log_var.data(), kSamples,
                 ray.target, ray.prior, terms, grad ? grad : &unused, d_mean, d_lv);
}

TEST(RayLoss, IsTheSumOfTheScaledTerms) {
  const Ray ray = RandomRay(3);
  for (float huber : {0.0f, 0.05f}) {
    const RayLossTerms t = AllTerms(huber);
    const double range = t.depth_range, scale = t.depth_scale / range;
    const double depth = ray.composite.depth / range, prior = ray.prior / range;
    double* none = nullptr;
    const double expected =
        RenderedColorL2(ray.composite.rgb, ray.target, double(t.rgb_l2_scale), none) +
        range * (huber > 0 ? DepthHuber(depth, prior, double(huber), scale, none)
                           : DepthL1(depth, prior, scale, none)) +
        RgbNll(ray.weights.data(), ray.mean_rgb.data(), ray.log_var.data(), kSamples, ray.target,
               double(t.variance_eps), double(t.nll_scale), none, none, none) +
        VarianceRegularizer(ray.log_var.data(), kSamples, double(t.variance_eps),
                            double(t.variance_reg_scale), none);
    EXPECT_NEAR(Loss(ray, t), expected, 1e-12);
  }
}

TEST(RayLoss, ZeroScalesLeaveTermsOutAndAnUnknownPriorAddsNothing) {
  Ray ray = RandomRay(4);
  RayLossTerms t;  // every scale 0
  render::RayCompositeGrad<double> grad;
  grad.depth = 7;  // overwritten
  EXPECT_EQ(Loss(ray, t, &grad), 0.0);
  EXPECT_EQ(grad.depth, 0.0);
  t.depth_scale = 1.0f;
  ray.prior = 0;  // no measurement
  EXPECT_EQ(Loss(ray, t, &grad), 0.0);
  EXPECT_EQ(grad.depth, 0.0);
}

TEST(RayLoss, GradientsMatchCentralDifferences) {
  for (float huber : {0.0f, 0.05f}) {
    Ray ray = RandomRay(11);
    const RayLossTerms t = AllTerms(huber);
    render::RayCompositeGrad<double> grad;
    std::vector<double> d_mean(3 * kSamples, 0.0), d_lv(kSamples, 0.0);
    Loss(ray, t, &grad, d_mean.data(), d_lv.data());
    const auto loss = [&] { return Loss(ray, t); };
    for (int c = 0; c < 3; ++c) {
      EXPECT_TRUE(CloseRelative(grad.rgb[c], CentralDifference(ray.composite.rgb[c], 1e-6, loss), 1e-7)) << c;
    }
    EXPECT_TRUE(CloseRelative(grad.depth, CentralDifference(ray.composite.depth, 1e-6, loss), 1e-7));
    for (int j = 0; j < kSamples; ++j) {
      EXPECT_TRUE(CloseRelative(d_lv[j], CentralDifference(ray.log_var[j], 1e-6, loss), 1e-7)) << j;
      for (int c = 0; c < 3; ++c) {
        EXPECT_TRUE(
            CloseRelative(d_mean[3 * j + c], CentralDifference(ray.mean_rgb[3 * j + c], 1e-6, loss), 1e-7))
            << j << "," << c;
      }
    }
  }
}

}  // namespace
}  // namespace endorecon::train
