// The training losses at the extremes (issue 6 §1): log-variances of +-80, variances at the floor,
// the NLL with a tiny variance and a large error. Outputs stay finite, match closed forms, and
// float32 agrees with a float64 evaluation of the same inputs to the tolerance stated per test.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "worker/engine/train/losses.h"

namespace endorecon::train {
namespace {

struct NllResult {
  double loss, d_weight, d_mean[3], d_log_var;
};

// One sample of weight w, mean colour mu and log-variance l against target colour t.
template <typename S>
NllResult Nll(double w, const double* mu, double l, const double* t, double eps) {
  const S ws = static_cast<S>(w), ls = static_cast<S>(l);
  const S mus[3] = {static_cast<S>(mu[0]), static_cast<S>(mu[1]), static_cast<S>(mu[2])};
  const S ts[3] = {static_cast<S>(t[0]), static_cast<S>(t[1]), static_cast<S>(t[2])};
  S d_w = 0, d_mu[3] = {0, 0, 0}, d_l = 0;
  const S loss = RgbNll(&ws, mus, &ls, 1, ts, static_cast<S>(eps), S(1), &d_w, d_mu, &d_l);
  return {loss, d_w, {d_mu[0], d_mu[1], d_mu[2]}, d_l};
}

bool AllFinite(const NllResult& r) {
  return std::isfinite(r.loss) && std::isfinite(r.d_weight) && std::isfinite(r.d_mean[0]) &&
         std::isfinite(r.d_mean[1]) && std::isfinite(r.d_mean[2]) && std::isfinite(r.d_log_var);
}

// |a - b| <= tol |b| + floor: float's relative precision with an absolute floor for values near 0.
void ExpectRelative(double a, double b, double tol, const char* what) {
  EXPECT_LE(std::fabs(a - b), tol * std::fabs(b) + 1e-30) << what << ": " << a << " vs " << b;
}

TEST(LossExtremes, NllIsFiniteForExtremeLogVariancesAndErrors) {
  const double zero[3] = {0, 0, 0}, one[3] = {1, 1, 1}, half[3] = {0.5, 0.5, 0.5};
  const double* targets[3] = {zero, one, half};
  for (double l : {-80.0, -30.0, 0.0, 30.0, 80.0}) {
    for (const double* t : targets) {
      for (double eps : {1e-6, 1e-3}) {
        // Float against double: 1e-5 relative on the loss and every gradient (a few float ulps
        // after the handful of operations per term).
        const NllResult f = Nll<float>(1.0, zero, l, t, eps), d = Nll<double>(1.0, zero, l, t, eps);
        ASSERT_TRUE(AllFinite(f)) << l << " " << eps;
        ASSERT_TRUE(AllFinite(d));
        ExpectRelative(f.loss, d.loss, 1e-5, "loss");
        ExpectRelative(f.d_weight, d.d_weight, 1e-5, "d_weight");
        for (int c = 0; c < 3; ++c) ExpectRelative(f.d_mean[c], d.d_mean[c], 1e-5, "d_mean");
        ExpectRelative(f.d_log_var, d.d_log_var, 1e-5, "d_log_var");
      }
    }
  }
}

TEST(LossExtremes, NllAtTheVarianceFloorWithLargeError) {
  // l = -80: softplus(l) ~ 1.8e-35, so var = eps; error |mu - C|^2 = 3 (the largest for colours in
  // [0, 1]). Loss = w (3 / (2 eps) + log(eps) / 2), d_mu = w (mu - C) / eps; d_l is tiny (sigmoid(-80)).
  const double mu[3] = {1, 1, 1}, target[3] = {0, 0, 0};
  for (double eps : {1e-6, 1e-9, 1e-12}) {
    const NllResult f = Nll<float>(0.5, mu, -80.0, target, eps);
    const double fe = static_cast<float>(eps);
    ASSERT_TRUE(AllFinite(f)) << eps;
    ExpectRelative(f.loss, 0.5 * (3 / (2 * fe) + 0.5 * std::log(fe)), 1e-5, "loss");
    ExpectRelative(f.d_mean[0], 0.5 / fe, 1e-5, "d_mean");
    EXPECT_LT(std::fabs(f.d_log_var), 1e-10);
  }
}

TEST(LossExtremes, NllWithHugeVarianceIsDominatedByTheLogTerm) {
  const double mu[3] = {1, 0, 1}, target[3] = {0, 1, 0};
  const NllResult f = Nll<float>(1.0, mu, 80.0, target, 1e-6);
  ASSERT_TRUE(AllFinite(f));
  ExpectRelative(f.loss, 3 / (2 * 80.0) + 0.5 * std::log(80.0), 1e-5, "loss");
  // d/dl = sigmoid(80) (1 - 3/80) / (2 * 80)
  ExpectRelative(f.d_log_var, (1 - 3 / 80.0) / 160.0, 1e-5, "d_log_var");
}

TEST(LossExtremes, RegulariserAtExtremeLogVariances) {
  const float log_var[4] = {-80.0f, 80.0f, -1e4f, 1e30f};
  float d[4] = {0, 0, 0, 0};
  const float eps = 1e-6f;
  const float loss = VarianceRegularizer(log_var, 4, eps, 1.0f, d);
  ASSERT_TRUE(std::isfinite(loss));
  const double expected =
      std::log1p(double{eps}) + std::log1p(80.0 + eps) + std::log1p(double{eps}) + std::log1p(1e30);
  ExpectRelative(loss, expected, 1e-5, "regulariser");
  for (float v : d) EXPECT_TRUE(std::isfinite(v));
  ExpectRelative(d[1], 1 / 81.0, 1e-5, "d at 80");
  EXPECT_EQ(d[2], 0.0f);  // sigmoid(-1e4) underflows to exactly 0
}

TEST(LossExtremes, DepthLossesOnHugeAndEmptyDepths) {
  float d = 0;
  EXPECT_EQ(DepthL1(0.0f, 5.0f, 1.0f, &d), 5.0f);  // an empty ray renders depth 0
  EXPECT_EQ(d, -1.0f);
  d = 0;
  const float huber = DepthHuber(1e30f, 1.0f, 0.1f, 1.0f, &d);
  EXPECT_TRUE(std::isfinite(huber));
  EXPECT_EQ(d, 0.1f);
  EXPECT_EQ(DepthHuber(3.0f, 0.0f, 0.1f, 1.0f, &d), 0.0f);  // unknown prior
}

}  // namespace
}  // namespace endorecon::train
