#include "worker/engine/field/mlp.h"

#include <gtest/gtest.h>

#include <cmath>
#include <type_traits>
#include <utility>
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

template <typename S>
struct MlpPass {
  std::vector<std::vector<S>> hidden;
  std::vector<S*> ptrs;
  std::vector<S> out;
};

template <typename S>
MlpPass<S> ForwardOf(Mlp<S>& mlp, const std::vector<S>& params, const std::vector<S>& in, int rows,
                     const DropoutPass& drop) {
  MlpPass<S> run;
  for (int k = 0; k < mlp.hidden_layers(); ++k) {
    run.hidden.emplace_back(static_cast<std::size_t>(rows) * mlp.hidden_dim(k));
  }
  for (auto& h : run.hidden) run.ptrs.push_back(h.data());
  run.out.resize(static_cast<std::size_t>(rows) * mlp.out_dim());
  mlp.Forward(params.data(), {rows, in.data()}, {run.ptrs.data(), run.out.data()}, drop);
  return run;
}

MlpRun Forward(Mlp<double>& mlp, const std::vector<double>& params, const std::vector<double>& in, int rows,
               const DropoutPass& drop) {
  MlpPass<double> run = ForwardOf(mlp, params, in, rows, drop);
  return {std::move(run.hidden), std::move(run.out)};
}

// dL/dparams (added to grads) and dL/din of a forward run.
template <typename S>
void BackwardOf(Mlp<S>& mlp, const std::vector<S>& params, const std::vector<S>& in, int rows,
                MlpPass<S>& run, const std::vector<S>& dout, std::vector<S>& grads,
                std::type_identity_t<std::vector<S>>* din, const DropoutPass& drop) {
  mlp.Backward(params.data(), {rows, in.data()}, {run.ptrs.data(), run.out.data()}, {dout.data()},
               grads.data(), {din ? din->data() : nullptr}, drop);
}

void CheckGradients(bool dropout_on) {
  Mlp<double> mlp(5, {7, 6}, 3, 0.3, 9);
  const int rows = 11;
  std::vector<double> params(mlp.param_count());
  mlp.Init(params.data(), 4);
  // Non-zero biases, so that every weight sees a non-trivial input.
  for (auto& p : params) p += 0.05;
  std::vector<double> in = RandomValues(static_cast<std::size_t>(rows) * 5, -1, 1, 5);
  const std::vector<double> w = RandomValues(static_cast<std::size_t>(rows) * 3, -1, 1, 6);
  const DropoutPass drop{dropout_on, 1234, 40};
  MlpPass<double> run = ForwardOf(mlp, params, in, rows, drop);
  std::vector<double> grads(mlp.param_count(), 0.0), din(in.size(), 0.0);
  BackwardOf(mlp, params, in, rows, run, w, grads, &din, drop);
  auto loss = [&] { return Dot(w, Forward(mlp, params, in, rows, drop).out); };
  EXPECT_GT(ExpectGradientMatches(params.data(), grads.data(), SomeIndices(params.size(), params.size(), 1),
                                  loss, "params"),
            50);
  EXPECT_GT(ExpectGradientMatches(in.data(), din.data(), SomeIndices(in.size(), in.size(), 2), loss, "input"),
            40);
}

TEST(MlpTest, GradientsMatchFiniteDifferences) { CheckGradients(false); }

TEST(MlpTest, GradientsMatchFiniteDifferencesWithDropout) { CheckGradients(true); }

// A batch of several tasks (per-task partial gradients, added in task order) gives the sum of the
// gradients of its parts, and adds to what the gradient array held.
TEST(MlpTest, BatchGradientIsTheSumOverItsParts) {
  Mlp<double> mlp(6, {9}, 4, 0.2, 5);
  std::vector<double> params(mlp.param_count());
  mlp.Init(params.data(), 2);
  const int rows = 5000, split = 3001;
  const auto in = RandomValues(static_cast<std::size_t>(rows) * 6, -1, 1, 3);
  const auto w = RandomValues(static_cast<std::size_t>(rows) * 4, -1, 1, 4);
  const DropoutPass drop{true, 11, 0};
  MlpPass<double> whole = ForwardOf(mlp, params, in, rows, drop);
  std::vector<double> grads(mlp.param_count(), 1.0);
  BackwardOf(mlp, params, in, rows, whole, w, grads, nullptr, drop);
  std::vector<double> parts(mlp.param_count(), 1.0);
  for (const auto& [first, count] : {std::pair{0, split}, std::pair{split, rows - split}}) {
    const std::vector<double> in_part(in.begin() + 6 * first, in.begin() + 6 * (first + count));
    const std::vector<double> w_part(w.begin() + 4 * first, w.begin() + 4 * (first + count));
    const DropoutPass part_drop{true, 11, static_cast<std::uint32_t>(first)};
    MlpPass<double> run = ForwardOf(mlp, params, in_part, count, part_drop);
    BackwardOf(mlp, params, in_part, count, run, w_part, parts, nullptr, part_drop);
  }
  for (std::size_t i = 0; i < grads.size(); ++i)
    ASSERT_NEAR(grads[i], parts[i], 1e-9 * (1 + std::abs(parts[i]))) << i;
}

TEST(MlpTest, LayerIsTheMatrixProduct) {
  Mlp<double> mlp(3, {}, 2, 0.0, 1);
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
  Mlp<double> mlp(1, {64}, 1, 0.25, 3);
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
  Mlp<double> mlp(4, {16}, 2, 0.5, 3);
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
  Mlp<double> md(20, {32, 33}, 17, 0.2, 4);
  Mlp<float> mf(20, {32, 33}, 17, 0.2, 4);
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
  MlpPass<double> rd = ForwardOf(md, pd, inr, rows, drop);
  MlpPass<float> rf = ForwardOf(mf, pf, inf, rows, drop);
  for (std::size_t i = 0; i < rf.out.size(); ++i) ASSERT_NEAR(rf.out[i], rd.out[i], 1e-4) << i;

  std::vector<double> grad_d(pd.size(), 0.0), din_d(inr.size());
  BackwardOf(md, pd, inr, rows, rd, gr, grad_d, &din_d, drop);
  std::vector<float> grad_f(pf.size(), 0.0f), din_f(inf.size());
  BackwardOf(mf, pf, inf, rows, rf, gf, grad_f, &din_f, drop);
  for (std::size_t i = 0; i < grad_f.size(); ++i) ASSERT_NEAR(grad_f[i], grad_d[i], 1e-3) << i;
  for (std::size_t i = 0; i < din_f.size(); ++i) ASSERT_NEAR(din_f[i], din_d[i], 1e-4) << i;
}

TEST(MlpTest, RejectsBadShapes) {
  EXPECT_THROW(Mlp<float>(0, {4}, 1, 0.0, 0), Error);
  EXPECT_THROW(Mlp<float>(3, {4}, 1, 1.0, 0), Error);
}

}  // namespace
}  // namespace endorecon::field
