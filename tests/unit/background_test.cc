// The learned background (field/background.h): its colours in closed form, its gradients against
// finite differences (the module's, and the training step's from a ray's loss through bg(d)), and the
// field that owns it.
#include "worker/engine/field/background.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numeric>
#include <vector>

#include "common/error.h"
#include "tests/unit/gradient_check.h"
#include "worker/engine/field/background_math.h"
#include "worker/engine/field/field.h"
#include "worker/engine/train/step_math.h"

namespace endorecon::field {
namespace {

using testing::Dot;
using testing::ExpectGradientMatches;
using testing::RandomValues;

double Logistic(double x) { return 1 / (1 + std::exp(-x)); }

// Unit directions, n x 3.
std::vector<double> RandomDirections(int n, std::uint64_t seed) {
  auto d = RandomValues(3 * std::size_t(n), -1, 1, seed);
  for (int i = 0; i < n; ++i) {
    const double l =
        std::sqrt(d[3 * i] * d[3 * i] + d[3 * i + 1] * d[3 * i + 1] + d[3 * i + 2] * d[3 * i + 2]);
    for (int c = 0; c < 3; ++c) d[3 * i + c] /= l;
  }
  return d;
}

TEST(BackgroundTest, GreyAtTheStartAndItsBandsInClosedForm) {
  Background<double> background;
  ASSERT_EQ(background.param_count(), std::size_t(kBackgroundParams));
  std::vector<double> params(background.param_count(), 1.0);
  background.Init(params.data(), 3);
  const double up[3] = {0, 0, 1}, down[3] = {0, 0, -1}, side[3] = {1, 0, 0};
  double rgb[3];
  BackgroundSample(params.data(), side, rgb);
  for (double v : rgb) EXPECT_EQ(v, 0.5);
  // Band 0 shifts red everywhere; Y_1^0 = 0.4886 z tilts green between up and down.
  params[0] = 2.0;
  params[3 * 2 + 1] = 3.0;
  BackgroundSample(params.data(), up, rgb);
  EXPECT_NEAR(rgb[0], Logistic(2.0 * 0.28209479177387814), 1e-15);
  EXPECT_NEAR(rgb[1], Logistic(3.0 * 0.48860251190291987), 1e-15);
  EXPECT_EQ(rgb[2], 0.5);
  BackgroundSample(params.data(), down, rgb);
  EXPECT_NEAR(rgb[0], Logistic(2.0 * 0.28209479177387814), 1e-15);
  EXPECT_NEAR(rgb[1], Logistic(-3.0 * 0.48860251190291987), 1e-15);
  BackgroundSample(params.data(), side, rgb);
  EXPECT_NEAR(rgb[1], 0.5, 1e-15);
}

TEST(BackgroundTest, GradientsMatchFiniteDifferences) {
  Background<double> background;
  const int n = 3000;  // several tasks' partials reduced
  auto params = RandomValues(background.param_count(), -0.8, 0.8, 1);
  const auto dir = RandomDirections(n, 2);
  const auto w = RandomValues(3 * std::size_t(n), -1, 1, 3);
  std::vector<double> rgb(3 * std::size_t(n));
  const auto loss = [&] {
    background.Forward(params.data(), {n, dir.data()}, {rgb.data()}, {});
    return Dot(w, rgb);
  };
  loss();
  std::vector<double> dparams(params.size(), 0.5);  // Backward adds
  background.Backward(params.data(), {n, dir.data()}, {rgb.data()}, {w.data()}, dparams.data(), {}, {});
  for (double& g : dparams) g -= 0.5;
  std::vector<std::size_t> all(params.size());
  std::iota(all.begin(), all.end(), 0);
  EXPECT_EQ(ExpectGradientMatches(params.data(), dparams.data(), all, loss, "background"), int(all.size()));
}

// One ray of a training step, in float as the step runs: its loss through bg(d) of its direction,
// differentiated by RayStepLoss (d_background) and BackgroundSampleBackward, against central
// differences of the loss in the background's parameters.
TEST(BackgroundTest, TheTrainingStepPassesARaysGradientToTheBackground) {
  constexpr int n = 4;
  std::vector<float> params(kBackgroundParams);
  for (int k = 0; k < kBackgroundParams; ++k) params[k] = 0.3f * std::sin(1.7f * float(k) + 0.4f);
  train::StepTables t;
  t.terms.rgb_l2_scale = 1.0f;
  t.samples = n;
  t.background_params = params.data();
  float target[3] = {0.9f, 0.2f, 0.4f}, prior = 0;
  float s[n] = {1, 2, 3, 4}, delta[n] = {0.2f, 0.2f, 0.2f, 0.2f};
  float sigma[n] = {0.5f, 0.8f, 0.3f, 0.2f}, sigma_lv[n] = {}, rgb_lv[n] = {}, weights[n];
  float rgb[3 * n] = {0.2f, 0.3f, 0.4f, 0.5f, 0.6f, 0.7f, 0.1f, 0.2f, 0.3f, 0.8f, 0.1f, 0.5f};
  float d_weights[n], d_sigma[n], d_rgb[3 * n], d_rgb_lv[n];
  float ray_dir[3], bg[3], d_bg[3];
  render::CameraRay camera_ray;
  camera_ray.direction[0] = 0.3;
  camera_ray.direction[1] = -0.5;
  camera_ray.direction[2] = 1.0;
  train::StepBatch b{};
  b.rays = 1;
  b.samples = n;
  b.target = target;
  b.prior = &prior;
  b.s = s;
  b.delta = delta;
  b.sigma = sigma;
  b.sigma_logvar = sigma_lv;
  b.rgb = rgb;
  b.rgb_logvar = rgb_lv;
  b.weights = weights;
  b.d_weights = d_weights;
  b.d_sigma = d_sigma;
  b.d_rgb = d_rgb;
  b.d_rgb_logvar = d_rgb_lv;
  b.ray_dir = ray_dir;
  b.background = bg;
  b.d_background = d_bg;
  b.camera_rays = &camera_ray;
  const double loss = train::RayStepLoss(t, b, 0).loss;
  ASSERT_GT(loss, 0);
  const double length = std::sqrt(0.3 * 0.3 + 0.5 * 0.5 + 1.0);
  EXPECT_NEAR(ray_dir[0], 0.3 / length, 1e-7);
  float expected_bg[3];
  BackgroundSample(params.data(), ray_dir, expected_bg);
  for (int c = 0; c < 3; ++c) EXPECT_EQ(bg[c], expected_bg[c]);
  std::vector<float> dparams(kBackgroundParams, 0.0f);
  BackgroundSampleBackward(ray_dir, bg, d_bg, dparams.data(), PlainAdd{});
  int nonzero = 0;
  for (int k = 0; k < kBackgroundParams; ++k) {
    const float h = 1e-2f, keep = params[k];
    params[k] = keep + h;
    const double up = train::RayStepLoss(t, b, 0).loss;
    params[k] = keep - h;
    const double down = train::RayStepLoss(t, b, 0).loss;
    params[k] = keep;
    const double numeric = (up - down) / (2 * h);
    EXPECT_NEAR(dparams[k], numeric, 2e-4 + 2e-3 * std::fabs(numeric)) << "background[" << k << "]";
    if (std::fabs(numeric) > 1e-6) ++nonzero;
  }
  EXPECT_GT(nonzero, 30);
}

FieldConfig TinyConfig() {
  FieldConfig config = FieldConfig::Cpu();
  config.grids.levels = 2;
  config.grids.log2_table = 8;
  return config;
}

TEST(BackgroundTest, AFieldOwnsItsBackgroundOnlyWhenConfigured) {
  FieldConfig config = TinyConfig();
  Field plain(config, 1);
  EXPECT_EQ(plain.background(), nullptr);
  for (const auto& block : plain.Blocks()) EXPECT_NE(block.name, "background");
  const float dir[3] = {0, 0, 1};
  float rgb[3];
  EXPECT_THROW(plain.BackgroundRgb(1, dir, rgb), Error);

  config.learned_background = true;
  Field field(config, 1);
  ASSERT_NE(field.background(), nullptr);
  const auto blocks = field.Blocks();
  ASSERT_EQ(blocks.back().name, "background");
  EXPECT_EQ(blocks.back().size, std::size_t(kBackgroundParams));
  blocks.back().value[0] = 1.0f;  // red up everywhere
  field.BackgroundRgb(1, dir, rgb);
  EXPECT_FLOAT_EQ(rgb[0], float(Logistic(0.28209479177387814)));
  EXPECT_FLOAT_EQ(rgb[1], 0.5f);
  const float drgb[3] = {1, 0, 0};
  field.ZeroGrad();
  field.BackgroundBackward(1, dir, rgb, drgb);
  EXPECT_FLOAT_EQ(blocks.back().grad[0], rgb[0] * (1 - rgb[0]) * 0.28209479177387814f);
}

}  // namespace
}  // namespace endorecon::field
