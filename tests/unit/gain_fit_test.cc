// Fitting a held-out frame's exposure: one least-squares gain per channel over the tissue.
#include "worker/engine/eval/gain_fit.h"

#include <gtest/gtest.h>

#include "common/error.h"
#include "worker/engine/eval/psnr.h"

namespace endorecon::eval {
namespace {

TEST(GainFitTest, AGainPerChannelUndoesAnExposureChange) {
  const int w = 8, h = 4;
  std::vector<std::uint8_t> reference(3 * w * h), mask(w * h, 0);
  std::vector<float> rendered(reference.size());
  const float exposure[3] = {0.8f, 1.0f, 1.25f};
  for (int p = 0; p < w * h; ++p) {
    for (int c = 0; c < 3; ++c) {
      reference[3 * p + c] = std::uint8_t(20 + 4 * p + 10 * c);  // times 1.25 still below 1
      rendered[3 * p + c] = reference[3 * p + c] / 255.0f * exposure[c];
    }
  }
  // A masked pixel that would pull the fit is left out.
  mask[3] = 1;
  rendered[9] = rendered[10] = rendered[11] = 1.0f;
  const GainFit fit = FitGain(rendered, reference, mask, w, h);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(fit.gain[c], 1.0 / exposure[c], 1e-6) << c;
  EXPECT_GT(Psnr(fit.rgb, reference, mask, w, h), 90.0);
  EXPECT_LT(Psnr(rendered, reference, mask, w, h), 25.0);
}

TEST(GainFitTest, AFittedRenderNeverScoresWorse) {
  const int w = 16, h = 16;
  std::vector<std::uint8_t> reference(3 * w * h);
  std::vector<float> rendered(reference.size());
  for (std::size_t i = 0; i < reference.size(); ++i) {
    reference[i] = std::uint8_t((i * 37) % 256);
    rendered[i] = float((i * 53) % 256) / 255.0f;  // unrelated: the best gain is still no worse than 1
  }
  const GainFit fit = FitGain(rendered, reference, {}, w, h);
  EXPECT_GE(Psnr(fit.rgb, reference, {}, w, h), Psnr(rendered, reference, {}, w, h));
}

TEST(GainFitTest, ABlackChannelKeepsGainOneAndSizesAreChecked) {
  const std::vector<std::uint8_t> reference(3 * 4, 100);
  std::vector<float> rendered(3 * 4, 0.0f);
  EXPECT_EQ(FitGain(rendered, reference, {}, 2, 2).gain[1], 1.0);
  EXPECT_THROW(FitGain(rendered, reference, {}, 3, 2), Error);
  EXPECT_THROW(FitGain(rendered, reference, std::vector<std::uint8_t>(3, 0), 2, 2), Error);
}

}  // namespace
}  // namespace endorecon::eval
