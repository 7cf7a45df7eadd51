#include "worker/engine/train/losses.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "tests/unit/central_difference.h"

namespace endorecon::train {
namespace {

using testing::CentralDifference;
using testing::CloseRelative;

constexpr double kEps = 1e-3;  // variance floor

struct Samples {
  std::vector<double> weights, mean_rgb, log_var;
  double target[3] = {0.3, 0.6, 0.1};
};

Samples RandomSamples(int n, unsigned seed) {
  std::mt19937 gen(seed);
  std::uniform_real_distribution<double> w(0.0, 0.3), c(0.0, 1.0), l(-4.0, 2.0);
  Samples out{std::vector<double>(n), std::vector<double>(3 * n), std::vector<double>(n)};
  for (int j = 0; j < n; ++j) {
    out.weights[j] = w(gen);
    out.log_var[j] = l(gen);
    for (int k = 0; k < 3; ++k) out.mean_rgb[3 * j + k] = c(gen);
  }
  return out;
}

TEST(RgbNll, MatchesTheFormula) {
  // One sample: w (|mu - C|^2 / (2 var) + log(var) / 2) with var = softplus(l) + eps.
  const double w = 0.7, mu[3] = {0.5, 0.5, 0.5}, target[3] = {0.2, 0.5, 0.9}, l = 0.3;
  const double var = std::log1p(std::exp(l)) + kEps;
  const double expected = w * ((0.09 + 0.16) / (2 * var) + 0.5 * std::log(var));
  const double got = RgbNll(&w, mu, &l, 1, target, kEps, 1.0, static_cast<double*>(nullptr),
                            static_cast<double*>(nullptr), static_cast<double*>(nullptr));
  EXPECT_NEAR(got, expected, 1e-14);
}

TEST(RgbNll, GradientsMatchCentralDifferences) {
  Samples x = RandomSamples(12, 5);
  const int n = 12;
  const double scale = 0.75;
  auto loss = [&] {
    return RgbNll(x.weights.data(), x.mean_rgb.data(), x.log_var.data(), n, x.target, kEps, scale,
                  static_cast<double*>(nullptr), static_cast<double*>(nullptr),
                  static_cast<double*>(nullptr));
  };
  std::vector<double> d_w(n, 0.0), d_mu(3 * n, 0.0), d_l(n, 0.0);
  RgbNll(x.weights.data(), x.mean_rgb.data(), x.log_var.data(), n, x.target, kEps, scale, d_w.data(),
         d_mu.data(), d_l.data());
  for (int j = 0; j < n; ++j) {
    EXPECT_TRUE(CloseRelative(d_w[j], CentralDifference(x.weights[j], 1e-6, loss), 1e-8)) << j;
    EXPECT_TRUE(CloseRelative(d_l[j], CentralDifference(x.log_var[j], 1e-6, loss), 1e-8)) << j;
    for (int c = 0; c < 3; ++c) {
      EXPECT_TRUE(CloseRelative(d_mu[3 * j + c], CentralDifference(x.mean_rgb[3 * j + c], 1e-6, loss), 1e-8));
    }
  }
}

// beta-NLL: the value is the NLL weighted by var^beta; the gradients are those of that loss with the
// weight var^beta held constant, which the finite differences see when the weights are pre-multiplied.
TEST(RgbNll, BetaWeighsEachTermByItsVarianceHeldConstant) {
  const int n = 10;
  const double scale = 0.5;
  for (double beta : {0.5, 1.0}) {
    Samples x = RandomSamples(n, 8);
    std::vector<double> frozen(n);
    for (int j = 0; j < n; ++j) {
      frozen[j] = x.weights[j] * std::pow(field::VarianceFromLogVar(x.log_var[j], kEps), beta);
    }
    double* none = nullptr;
    const double beta_loss = RgbNll(x.weights.data(), x.mean_rgb.data(), x.log_var.data(), n, x.target, kEps,
                                    scale, none, none, none, beta);
    EXPECT_NEAR(beta_loss,
                RgbNll(frozen.data(), x.mean_rgb.data(), x.log_var.data(), n, x.target, kEps, scale, none,
                       none, none),
                1e-12);
    std::vector<double> d_w(n, 0.0), d_mu(3 * n, 0.0), d_l(n, 0.0);
    RgbNll(x.weights.data(), x.mean_rgb.data(), x.log_var.data(), n, x.target, kEps, scale, d_w.data(),
           d_mu.data(), d_l.data(), beta);
    auto with_frozen = [&] {
      return RgbNll(frozen.data(), x.mean_rgb.data(), x.log_var.data(), n, x.target, kEps, scale, none, none,
                    none);
    };
    for (int j = 0; j < n; ++j) {
      EXPECT_TRUE(CloseRelative(d_l[j], CentralDifference(x.log_var[j], 1e-6, with_frozen), 1e-7)) << j;
      EXPECT_TRUE(CloseRelative(d_w[j] * x.weights[j],
                                CentralDifference(frozen[j], 1e-6, with_frozen) * frozen[j], 1e-7))
          << j;
      for (int c = 0; c < 3; ++c) {
        EXPECT_TRUE(CloseRelative(d_mu[3 * j + c],
                                  CentralDifference(x.mean_rgb[3 * j + c], 1e-6, with_frozen), 1e-7));
      }
    }
    if (beta == 1.0) {
      // The mean's gradient is that of w |mu - C|^2 / 2: no 1 / var.
      for (int c = 0; c < 3; ++c) {
        EXPECT_NEAR(d_mu[c], scale * x.weights[0] * (x.mean_rgb[c] - x.target[c]), 1e-12);
      }
    }
  }
}

// The variance that minimises one sample's NLL for a colour error of `levels` 8-bit steps in one
// channel (golden-section search over the log-variance; the NLL is unimodal in it).
double NllMinimisingVariance(double levels, double eps) {
  const double weight = 1, mu[3] = {0.5 + levels / 255.0, 0.5, 0.5}, target[3] = {0.5, 0.5, 0.5};
  const auto loss = [&](double l) {
    return RgbNll(&weight, mu, &l, 1, target, eps, 1.0, static_cast<double*>(nullptr),
                  static_cast<double*>(nullptr), static_cast<double*>(nullptr));
  };
  const double ratio = (std::sqrt(5.0) - 1) / 2;
  double lo = -40, hi = 5;
  for (int i = 0; i < 200; ++i) {
    const double a = hi - ratio * (hi - lo), b = lo + ratio * (hi - lo);
    if (loss(a) < loss(b)) {
      hi = b;
    } else {
      lo = a;
    }
  }
  return field::VarianceFromLogVar((lo + hi) / 2, eps);
}

TEST(RgbNll, TheDefaultFloorLetsTheVarianceRankErrorsOfOneIntensityLevel) {
  // Above the floor the minimiser is var = |mu - C|^2, so twice the error gives four times the
  // variance; a floor above the errors (the old 1e-3, an error of 8/255) gives both the floor.
  const double eps = field::kDefaultVarianceEps;
  const double one = NllMinimisingVariance(1, eps), two = NllMinimisingVariance(2, eps);
  EXPECT_NEAR(one, 1 / (255.0 * 255.0), 0.05 / (255.0 * 255.0));
  EXPECT_NEAR(two / one, 4.0, 0.2);
  EXPECT_LT(NllMinimisingVariance(2, 1e-3) / NllMinimisingVariance(1, 1e-3), 1.01);
}

TEST(RenderedColorL2, ValueAndGradient) {
  double rendered[3] = {0.2, 0.9, 0.4};
  const double target[3] = {0.5, 0.5, 0.5};
  EXPECT_NEAR(RenderedColorL2(rendered, target, 1.0, static_cast<double*>(nullptr)), 0.09 + 0.16 + 0.01,
              1e-15);
  double d[3] = {0, 0, 0};
  RenderedColorL2(rendered, target, 2.0, d);
  for (int c = 0; c < 3; ++c) {
    const double fd = CentralDifference(rendered[c], 1e-6, [&] {
      return RenderedColorL2(rendered, target, 2.0, static_cast<double*>(nullptr));
    });
    EXPECT_NEAR(d[c], fd, 1e-8);
  }
}

TEST(DepthLoss, L1AndHuberMatchCentralDifferences) {
  const double prior = 4.0, huber_delta = 0.5;
  for (double rendered : {3.1, 3.8, 4.3, 5.2}) {  // both Huber branches, both signs, away from kinks
    double d_l1 = 0, d_huber = 0;
    DepthL1(rendered, prior, 1.5, &d_l1);
    DepthHuber(rendered, prior, huber_delta, 1.5, &d_huber);
    double x = rendered;
    const double fd_l1 =
        CentralDifference(x, 1e-6, [&] { return DepthL1(x, prior, 1.5, static_cast<double*>(nullptr)); });
    const double fd_huber = CentralDifference(
        x, 1e-6, [&] { return DepthHuber(x, prior, huber_delta, 1.5, static_cast<double*>(nullptr)); });
    EXPECT_NEAR(d_l1, fd_l1, 1e-8) << rendered;
    EXPECT_NEAR(d_huber, fd_huber, 1e-8) << rendered;
  }
  EXPECT_NEAR(DepthL1(3.0, prior, 1.0, static_cast<double*>(nullptr)), 1.0, 1e-15);
  EXPECT_NEAR(DepthHuber(4.2, prior, huber_delta, 1.0, static_cast<double*>(nullptr)), 0.5 * 0.04, 1e-15);
  EXPECT_NEAR(DepthHuber(6.0, prior, huber_delta, 1.0, static_cast<double*>(nullptr)), 0.5 * (2.0 - 0.25),
              1e-15);
}

TEST(DepthLoss, UnknownPriorIsSkipped) {
  for (double prior : {0.0, -1.0, std::nan(""), HUGE_VAL}) {
    double d = 0;
    EXPECT_EQ(DepthL1(3.0, prior, 1.0, &d), 0.0);
    EXPECT_EQ(DepthHuber(3.0, prior, 0.5, 1.0, &d), 0.0);
    EXPECT_EQ(d, 0.0);
  }
}

TEST(VarianceRegularizer, ValueAndGradient) {
  Samples x = RandomSamples(6, 9);
  double expected = 0;
  for (double l : x.log_var) expected += std::log(1 + std::log1p(std::exp(l)) + kEps);
  EXPECT_NEAR(VarianceRegularizer(x.log_var.data(), 6, kEps, 1.0, static_cast<double*>(nullptr)), expected,
              1e-13);
  std::vector<double> d(6, 0.0);
  VarianceRegularizer(x.log_var.data(), 6, kEps, 0.01, d.data());
  for (int j = 0; j < 6; ++j) {
    const double fd = CentralDifference(x.log_var[j], 1e-6, [&] {
      return VarianceRegularizer(x.log_var.data(), 6, kEps, 0.01, static_cast<double*>(nullptr));
    });
    EXPECT_TRUE(CloseRelative(d[j], fd, 1e-9)) << j;
  }
}

TEST(RgbNll, GradientsAddUpAcrossTerms) {
  // The NLL and the regulariser both write d_log_var: their sum must be the sum of each alone.
  const Samples x = RandomSamples(4, 2);
  std::vector<double> nll_only(4, 0.0), reg_only(4, 0.0), both(4, 0.0);
  RgbNll(x.weights.data(), x.mean_rgb.data(), x.log_var.data(), 4, x.target, kEps, 1.0,
         static_cast<double*>(nullptr), static_cast<double*>(nullptr), nll_only.data());
  VarianceRegularizer(x.log_var.data(), 4, kEps, 0.1, reg_only.data());
  RgbNll(x.weights.data(), x.mean_rgb.data(), x.log_var.data(), 4, x.target, kEps, 1.0,
         static_cast<double*>(nullptr), static_cast<double*>(nullptr), both.data());
  VarianceRegularizer(x.log_var.data(), 4, kEps, 0.1, both.data());
  for (int j = 0; j < 4; ++j) EXPECT_DOUBLE_EQ(both[j], nll_only[j] + reg_only[j]);
}

}  // namespace
}  // namespace endorecon::train
