#include "worker/engine/field/exposure.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numeric>
#include <opencv2/core.hpp>
#include <vector>

#include "common/error.h"
#include "tests/unit/gradient_check.h"
#include "worker/engine/field/exposure_math.h"
#include "worker/engine/scene/exposure_change.h"

namespace endorecon::field {
namespace {

using testing::Dot;
using testing::ExpectGradientMatches;
using testing::RandomValues;

const std::vector<float> kTimes = {0.1f, 0.3f, 0.7f};

TEST(ExposureTest, KnotsAroundATime) {
  int k0 = -1, k1 = -1;
  double w = -1;
  ExposureKnots(kTimes.data(), 3, 0.2, &k0, &k1, &w);
  EXPECT_EQ(k0, 0);
  EXPECT_EQ(k1, 1);
  EXPECT_NEAR(w, 0.5, 1e-6);
  ExposureKnots(kTimes.data(), 3, 0.6, &k0, &k1, &w);
  EXPECT_EQ(k0, 1);
  EXPECT_EQ(k1, 2);
  EXPECT_NEAR(w, 0.75, 1e-6);
  ExposureKnots(kTimes.data(), 3, double(kTimes[1]), &k0, &k1, &w);  // on a knot: that knot alone
  EXPECT_DOUBLE_EQ((1 - w) * (k0 == 1) + w * (k1 == 1), 1.0);
  for (const double t : {0.0, 0.1, -5.0, double(NAN)}) {  // before the first knot, and NaN: the first
    ExposureKnots(kTimes.data(), 3, t, &k0, &k1, &w);
    EXPECT_EQ(k0, 0) << t;
    EXPECT_EQ(w, 0.0) << t;
  }
  ExposureKnots(kTimes.data(), 3, 0.9, &k0, &k1, &w);  // after the last: the last
  EXPECT_EQ(k0, 2);
  EXPECT_EQ(k1, 2);
  ExposureKnots(kTimes.data(), 1, 0.5, &k0, &k1, &w);  // one knot: everywhere
  EXPECT_EQ(k0, 0);
  EXPECT_EQ(k1, 0);
}

// A gain of e^a on a knot; off the knots (between them or past the ends) the blend, or the end knot's,
// shrunk toward the mean by rho.
TEST(ExposureTest, GainsInClosedForm) {
  Exposure<double> exposure(kTimes);
  std::vector<double> params(exposure.param_count());
  exposure.Init(params.data(), 1);
  for (const double p : params) EXPECT_EQ(p, 0.0);  // a gain of 1 to start
  // Neighbouring knots anticorrelated (a flicker): rho clamps to 0, and a time between two knots gets
  // the mean log-gain.
  params = {0.2, 0, -0.1, /**/ -0.4, 0.1, 0.0, /**/ 0, 0, 0};
  double prior[kExposurePriorSize];
  ExposurePrior(params.data(), 3, prior);
  EXPECT_NEAR(prior[0], -0.2 / 3, 1e-12);
  EXPECT_EQ(prior[3], 0.0);
  const std::vector<double> time = {0.1, 0.2, 0.9};
  const std::vector<double> rgb = {0.5, 0.5, 0.5, 0.5, 0.5, 0.5, 0.25, 0.5, 1.0};
  std::vector<double> out(9);
  exposure.Forward(params.data(), {3, time.data(), rgb.data()}, {out.data()}, {});
  EXPECT_NEAR(out[0], 0.5 * std::exp(0.2), 1e-7);  // on the first knot (a float time)
  EXPECT_NEAR(out[2], 0.5 * std::exp(-0.1), 1e-7);
  EXPECT_NEAR(out[3], 0.5 * std::exp(-0.2 / 3), 1e-12);
  EXPECT_NEAR(out[4], 0.5 * std::exp(0.1 / 3), 1e-12);
  // Past the last knot no frame was trained either: the mean too (the last knot's own gain, 1, is one
  // draw of the flicker).
  EXPECT_NEAR(out[6], 0.25 * std::exp(-0.2 / 3), 1e-12);
  EXPECT_NEAR(out[8], 1.0 * std::exp(-0.1 / 3), 1e-12);
}

// The module computes the gains once per run of equal times (a ray's samples, a frame's rays): its
// output is, bit for bit, the per-sample function's (the CUDA kernels' form) on runs, on times that
// alternate, across task boundaries and on NaN.
TEST(ExposureTest, TheBatchEqualsThePerSampleMathBitForBit) {
  const std::vector<float> times = {0.0f, 0.2f, 0.4f, 0.5f, 0.8f, 1.0f};
  Exposure<float> exposure(times);
  const auto params64 = RandomValues(exposure.param_count(), -0.2, 0.2, 5);
  const std::vector<float> params(params64.begin(), params64.end());
  const int n = 5000;  // three tasks
  std::vector<float> time(n), rgb(3 * n), out(3 * n);
  for (int i = 0; i < n; ++i) {
    time[i] = i < 2100 ? float(i / 24) / 90.0f : (i % 2 ? 0.35f : 0.9f);  // runs of 24, then alternating
    for (int c = 0; c < 3; ++c) rgb[3 * i + c] = 0.1f + 0.8f * float((7 * i + c) % 11) / 10.0f;
  }
  time[100] = time[4000] = NAN;
  exposure.Forward(params.data(), {n, time.data(), rgb.data()}, {out.data()}, {});
  float prior[kExposurePriorSize];
  ExposurePrior(params.data(), exposure.knots(), prior);
  int equal = 0;
  for (int i = 0; i < n; ++i) {
    float expected[3];
    ExposureSample(params.data(), prior, times.data(), exposure.knots(), time[i], rgb.data() + 3 * i,
                   expected);
    for (int c = 0; c < 3; ++c) equal += out[3 * i + c] == expected[c];
  }
  EXPECT_EQ(equal, 3 * n);
}

TEST(ExposureTest, PriorOfAFlickerADriftAndASteadyExposure) {
  double prior[kExposurePriorSize];
  // A ramp over five knots: mean 0.2; centred -0.2 .. 0.2, lag sum 0.04 over a variance sum of 0.1.
  const std::vector<double> ramp = {0, 0, 0, 0.1, 0.1, 0.1, 0.2, 0.2, 0.2, 0.3, 0.3, 0.3, 0.4, 0.4, 0.4};
  ExposurePrior(ramp.data(), 5, prior);
  EXPECT_NEAR(prior[1], 0.2, 1e-12);
  EXPECT_NEAR(prior[3], 0.4, 1e-12);
  // Halfway between the second and third knots: the blend 0.15 shrunk toward 0.2 by 0.4.
  const float times[5] = {0.0f, 0.25f, 0.5f, 0.75f, 1.0f};
  bool unseen = false;
  EXPECT_NEAR(ExposureLogGain(ramp.data(), prior, times, 0.375, 1, 2, 0.5, 0, &unseen),
              0.2 + 0.4 * (0.15 - 0.2), 1e-12);
  EXPECT_TRUE(unseen);
  EXPECT_NEAR(ExposureLogGain(ramp.data(), prior, times, 0.25, 1, 2, 0.0, 0, &unseen), 0.1, 1e-12);  // a knot
  EXPECT_FALSE(unseen);
  EXPECT_NEAR(ExposureLogGain(ramp.data(), prior, times, 1.0, 4, 4, 0.0, 0, &unseen), 0.4,
              1e-12);  // the last
  EXPECT_FALSE(unseen);
  // Past the last knot: its 0.4 shrunk toward 0.2 by 0.4, as a time between knots.
  EXPECT_NEAR(ExposureLogGain(ramp.data(), prior, times, 1.2, 4, 4, 0.0, 0, &unseen), 0.2 + 0.4 * (0.4 - 0.2),
              1e-12);
  EXPECT_TRUE(unseen);
  const std::vector<double> steady(12, 0.3);
  ExposurePrior(steady.data(), 4, prior);
  EXPECT_EQ(prior[3], 1.0);
}

TEST(ExposureTest, GradientsMatchFiniteDifferences) {
  const std::vector<float> times = {0.0f, 0.2f, 0.4f, 0.5f, 0.8f, 1.0f};
  Exposure<double> exposure(times);
  const int n = 5000;  // three tasks' partials reduced
  // A drift with jitter: rho inside (0, 1), so its gradient is checked too.
  auto params = RandomValues(exposure.param_count(), -0.05, 0.05, 1);
  for (std::size_t k = 0; k < params.size(); ++k) params[k] += 0.1 * double(k / 3);
  double prior[kExposurePriorSize];
  ExposurePrior(params.data(), 6, prior);
  ASSERT_GT(prior[3], 0.05);
  ASSERT_LT(prior[3], 0.95);
  auto time = RandomValues(n, -0.1, 1.1, 2);
  for (int i = 0; i < n; i += 10) time[i] = times[(i / 10) % 6];  // some samples on knots
  auto rgb = RandomValues(3 * n, 0.05, 0.95, 3);
  const auto w = RandomValues(3 * n, -1, 1, 4);
  std::vector<double> out(3 * n);
  const auto loss = [&] {
    exposure.Forward(params.data(), {n, time.data(), rgb.data()}, {out.data()}, {});
    return Dot(w, out);
  };
  std::vector<double> dparams(params.size(), 0.0), drgb(3 * n);
  exposure.Backward(params.data(), {n, time.data(), rgb.data()}, {}, {w.data()}, dparams.data(),
                    {drgb.data()}, {});
  std::vector<std::size_t> all(params.size());
  std::iota(all.begin(), all.end(), 0);
  EXPECT_EQ(ExpectGradientMatches(params.data(), dparams.data(), all, loss, "log-gains", {1e-6, 1e-6, 1e-8}),
            int(all.size()));
  EXPECT_GT(ExpectGradientMatches(rgb.data(), drgb.data(), {0, 1, 2, 3000, 7001, 14999}, loss, "colour"), 0);
}

TEST(ExposureTest, KnotsMustAscend) {
  EXPECT_THROW(Exposure<float>({}), Error);
  EXPECT_THROW(Exposure<float>({0.5f, 0.5f}), Error);
  EXPECT_THROW(Exposure<float>({0.1f, NAN}), Error);
  EXPECT_NO_THROW(Exposure<float>({0.5f}));
}

// Two 40 x 30 frames of a textured scene; the second `gain` times as bright, its left third moved.
scene::Clip TwoFrames(double gain, bool with_tool) {
  scene::Clip clip;
  clip.width = 40;
  clip.height = 30;
  const std::size_t pixels = 40 * 30;
  clip.rgb.assign(2, std::vector<std::uint8_t>(3 * pixels));
  for (std::size_t p = 0; p < pixels; ++p) {
    for (int c = 0; c < 3; ++c) {
      const double v = 40 + 30 * c + (p * 37 % 101);
      clip.rgb[0][3 * p + c] = std::uint8_t(v);
      const bool moved = p % 40 < 13;
      clip.rgb[1][3 * p + c] = std::uint8_t(std::lround((moved ? 40 + 30 * c + (p * 53 % 101) : v) * gain));
    }
  }
  if (with_tool) {  // a white tool over the bottom half of the second frame, masked
    clip.tool_mask.assign(2, std::vector<std::uint8_t>(pixels, 0));
    for (std::size_t p = pixels / 2; p < pixels; ++p) {
      clip.tool_mask[1][p] = 1;
      for (int c = 0; c < 3; ++c) clip.rgb[1][3 * p + c] = 200;
    }
  }
  return clip;
}

TEST(ExposureChangeTest, MeasuresAWholeFrameGainDespiteMotionAndTools) {
  EXPECT_NEAR(scene::ExposureChange(TwoFrames(1.1, false), {0, 1}), std::log(1.1), 0.01);
  EXPECT_NEAR(scene::ExposureChange(TwoFrames(1.1, true), {0, 1}), std::log(1.1), 0.01);
  EXPECT_LT(scene::ExposureChange(TwoFrames(1.0, true), {0, 1}), 0.003);
  EXPECT_EQ(scene::ExposureChange(TwoFrames(1.1, false), {0}), 0.0);
}

// Noise, or a handful of pixels, is no exposure change: a noisy clip's and a 10 x 8 clip's medians
// strayed past the threshold and turned the gains on (found 2026-12-06).
TEST(ExposureChangeTest, NoiseOrAFewPixelsAreNoChange) {
  scene::Clip noisy = TwoFrames(1.0, false);
  cv::RNG random(3);
  for (auto& frame : noisy.rgb) {
    for (auto& v : frame) v = cv::saturate_cast<std::uint8_t>(v + random.gaussian(12));
  }
  EXPECT_LT(scene::ExposureChange(noisy, {0, 1}), 0.002);
  scene::Clip gained = TwoFrames(1.1, false);
  for (auto& frame : gained.rgb) {
    for (auto& v : frame) v = cv::saturate_cast<std::uint8_t>(v + random.gaussian(12));
  }
  EXPECT_GT(scene::ExposureChange(gained, {0, 1}), 0.05) << "a real gain still shows through the noise";
  scene::Clip tiny = TwoFrames(1.1, false);
  tiny.width = 10;
  tiny.height = 8;
  for (auto& frame : tiny.rgb) frame.resize(3 * 10 * 8);
  EXPECT_EQ(scene::ExposureChange(tiny, {0, 1}), 0.0) << "12 pixels a channel say nothing";
}

}  // namespace
}  // namespace endorecon::field
