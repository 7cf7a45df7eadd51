#include "worker/engine/field/mlp.h"

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

struct MlpRun {
  std::vector<std::vector<double>> hidden;
  std::vector<double> out;
};

MlpRun Forward(const Mlp<double>& mlp, const std::vector<double>& params, const std::vector<double>& in,
               int rows, const DropoutPass& drop) {
  MlpRun run;
  std::vector<double*> ptrs;
  for (int k = 0; k < mlp.hidden_layers(); ++k) {
    run.hidden.emplace_back(static_cast<std::size_t>(rows) * mlp.hidden_dim(k));
  }
  for (auto& h : run.hidden) ptrs.push_back(h.data());
  run.out.resize(static_cast<std::size_t>(rows) * mlp.out_dim());
  mlp.Forward(params.data(), in.data(), rows, ptrs.data(), run.out.data(), drop);
  return run;
}

void CheckGradients(bool dropout_on) {
  const Mlp<double> mlp(5, {7, 6}, 3, 0.3, 9);
  const int rows = 11;
  std::vector<double> params(mlp.param_count());
  mlp.Init(params.data(), 4);
  // Non-zero biases, so that every weight sees a non-trivial input.
  for (auto& p : params) p += 0.05;
  std::vector<double> in = RandomValues(static_cast<std::size_t>(rows) * 5, -1, 1, 5);
  const std::vector<double> w = RandomValues(static_cast<std::size_t>(rows) * 3, -1, 1, 6);
  const DropoutPass drop{dropout_on, 1234, 40};
  const MlpRun run = Forward(mlp, params, in, rows, drop);
  std::vector<const double*> hidden;
  for (const auto& h : run.hidden) hidden.push_back(h.data());
  std::vector<double> grads(mlp.param_count(), 0.0), din(in.size(), 0.0);
  std::vector<double> scratch(mlp.scratch_size(rows));
  mlp.Backward(params.data(), in.data(), rows, hidden.data(), w.data(), din.data(), grads.data(),
               scratch.data(), dropout_on);
  auto loss = [&] { return Dot(w, Forward(mlp, params, in, rows, drop).out); };
  EXPECT_GT(ExpectGradientMatches(params.data(), grads.data(), SomeIndices(params.size(), params.size(), 1),
                                  loss, "params"),
            50);
  EXPECT_GT(ExpectGradientMatches(in.data(), din.data(), SomeIndices(in.size(), in.size(), 2), loss, "input"),
            40);
}

TEST(MlpTest, GradientsMatchFiniteDifferences) { CheckGradients(false); }

TEST(MlpTest, GradientsMatchFiniteDifferencesWithDropout) { CheckGradients(true); }

TEST(MlpTest, LayerIsTheMatrixProduct) {
  const Mlp<double> mlp(3, {}, 2, 0.0, 1);
  const std::vector<double> params = {1, 2, 3, 4, 5, 6, 0.5, -0.5};  // W (3 x 2) row-major, then b
  const std::vector<double> in = {1, 0, -1, 2, 1, 0};
  const MlpRun run = Forward(mlp, params, in, 2, {});
  EXPECT_DOUBLE_EQ(run.out[0], 1 * 1 + 0 * 3 - 1 * 5 + 0.5);
  EXPECT_DOUBLE_EQ(run.out[1], 1 * 2 + 0 * 4 - 1 * 6 - 0.5);
  EXPECT_DOUBLE_EQ(run.out[2], 2 * 1 + 1 * 3 + 0.5);
  EXPECT_DOUBLE_EQ(run.out[3], 2 * 2 + 1 * 4 - 0.5);
  EXPECT_EQ(mlp.macs_per_sample(), 6u);
}

TEST(MlpTest, DropoutDropsItsRateAndScalesSurvivors) {
  // A hidden layer whose pre-activations are all exactly 1.
  const Mlp<double> mlp(1, {64}, 1, 0.25, 3);
  std::vector<double> params(mlp.param_count(), 0.0);
  for (int j = 0; j < 64; ++j) params[j] = 1.0;
  const int rows = 500;
  const std::vector<double> in(rows, 1.0);
  const MlpRun off = Forward(mlp, params, in, rows, {false, 9, 0});
  for (double h : off.hidden[0]) ASSERT_EQ(h, 1.0);
  const MlpRun on = Forward(mlp, params, in, rows, {true, 9, 0});
  int dropped = 0;
  for (double h : on.hidden[0]) {
    if (h == 0.0) {
      ++dropped;
    } else {
      EXPECT_DOUBLE_EQ(h, 1.0 / 0.75);
    }
  }
  EXPECT_NEAR(dropped / (64.0 * rows), 0.25, 0.01);
  // Another seed gives another mask.
  const MlpRun other = Forward(mlp, params, in, rows, {true, 10, 0});
  EXPECT_NE(other.hidden[0], on.hidden[0]);
}

TEST(MlpTest, DropoutMaskDoesNotDependOnTiling) {
  const Mlp<double> mlp(4, {16}, 2, 0.5, 3);
  std::vector<double> params(mlp.param_count());
  mlp.Init(params.data(), 1);
  const int rows = 30;
  const std::vector<double> in = RandomValues(4 * rows, -1, 1, 2);
  const MlpRun whole = Forward(mlp, params, in, rows, {true, 77, 0});
  const std::vector<double> tail(in.begin() + 4 * 12, in.end());
  const MlpRun part = Forward(mlp, params, tail, rows - 12, {true, 77, 12});
  for (int i = 0; i < 2 * (rows - 12); ++i) EXPECT_EQ(part.out[i], whole.out[2 * 12 + i]) << i;
}

// The float network (what the field trains) agrees with the double one the gradient checks use.
TEST(MlpTest, FloatAgreesWithDouble) {
  const Mlp<double> md(20, {32, 33}, 17, 0.2, 4);
  const Mlp<float> mf(20, {32, 33}, 17, 0.2, 4);
  const int rows = 77;
  std::vector<double> pd(md.param_count());
  md.Init(pd.data(), 3);
  for (auto& p : pd) p += 0.01;
  const std::vector<float> pf(pd.begin(), pd.end());
  const auto ind = RandomValues(static_cast<std::size_t>(rows) * 20, -1, 1, 5);
  const auto gd = RandomValues(static_cast<std::size_t>(rows) * 17, -1, 1, 6);
  const std::vector<float> inf(ind.begin(), ind.end()), gf(gd.begin(), gd.end());
  const std::vector<double> inr(inf.begin(), inf.end()), gr(gf.begin(), gf.end());
  const DropoutPass drop{true, 8, 0};
  const MlpRun rd = Forward(md, pd, inr, rows, drop);
  std::vector<float> h0(rows * 32), h1(rows * 33), outf(rows * 17);
  float* hidden[2] = {h0.data(), h1.data()};
  mf.Forward(pf.data(), inf.data(), rows, hidden, outf.data(), drop);
  for (std::size_t i = 0; i < outf.size(); ++i) ASSERT_NEAR(outf[i], rd.out[i], 1e-4) << i;

  std::vector<double> grad_d(pd.size(), 0.0), din_d(inr.size()), scratch_d(md.scratch_size(rows));
  const double* hd[2] = {rd.hidden[0].data(), rd.hidden[1].data()};
  md.Backward(pd.data(), inr.data(), rows, hd, gr.data(), din_d.data(), grad_d.data(), scratch_d.data(),
              true);
  std::vector<float> grad_f(pf.size(), 0.0f), din_f(inf.size()), scratch_f(mf.scratch_size(rows));
  const float* hf[2] = {h0.data(), h1.data()};
  mf.Backward(pf.data(), inf.data(), rows, hf, gf.data(), din_f.data(), grad_f.data(), scratch_f.data(),
              true);
  for (std::size_t i = 0; i < grad_f.size(); ++i) ASSERT_NEAR(grad_f[i], grad_d[i], 1e-3) << i;
  for (std::size_t i = 0; i < din_f.size(); ++i) ASSERT_NEAR(din_f[i], din_d[i], 1e-4) << i;
}

TEST(MlpTest, RejectsBadShapes) {
  EXPECT_THROW(Mlp<float>(0, {4}, 1, 0.0, 0), Error);
  EXPECT_THROW(Mlp<float>(3, {4}, 1, 1.0, 0), Error);
}

}  // namespace
}  // namespace endorecon::field
