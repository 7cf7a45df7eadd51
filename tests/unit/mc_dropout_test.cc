// Monte Carlo dropout moments with known answers, and the FrameRenderer's uncertainty mode on a
// constructed field: no dropout means no epistemic variance, exactly.
#include "worker/engine/render/mc_dropout.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "tests/unit/small_render_scene.h"
#include "worker/engine/field/variance.h"
#include "worker/engine/render/frame_renderer.h"
#include "worker/engine/scene/scene_box.h"

namespace endorecon::render {
namespace {

TEST(McDropout, MomentsOfKnownPasses) {
  const double x[4] = {1e4 + 1, 1e4 + 3, 1e4 + 5, 1e4 + 7};  // a large mean with a small spread
  const double var[4] = {0.5, 1.0, 1.5, 3.0};
  McMoments<double> m;
  for (int k = 0; k < 4; ++k) AddPass(m, k + 1, x[k], var[k]);
  EXPECT_DOUBLE_EQ(m.mean, 1e4 + 4);
  EXPECT_DOUBLE_EQ(Epistemic(m, 4), 5.0);  // population variance of 1, 3, 5, 7
  EXPECT_DOUBLE_EQ(Aleatoric(m, 4), 1.5);
  McMoments<float> constant;
  for (int k = 1; k <= 8; ++k) AddPass(constant, k, 123.456f, 0.25f);
  EXPECT_EQ(constant.mean, 123.456f);
  EXPECT_EQ(Epistemic(constant, 8), 0.0f);
}

using testing::SmallField;

RenderedFrame RenderWith(field::Field& field, int passes) {
  const scene::Camera camera = testing::SmallCamera();
  FrameRenderer renderer(field, scene::FrustumBox({camera}, 0.5, 2.0), testing::SmallRenderSettings(passes));
  return renderer.Render(camera, 0.3f);
}

TEST(McDropout, NoDropoutMeansNoEpistemicVariance) {
  field::Field field(SmallField(0.0), 4);
  const RenderedFrame plain = RenderWith(field, 0);
  const RenderedFrame mc = RenderWith(field, 5);
  EXPECT_TRUE(plain.uncertainty.empty());
  ASSERT_EQ(mc.uncertainty.size(), 120u);
  EXPECT_EQ(mc.rgb, plain.rgb);  // K identical passes average to the single pass exactly
  for (int i = 0; i < 120; ++i) {
    EXPECT_EQ(mc.epistemic[i], 0.0f) << i;
    EXPECT_GT(mc.aleatoric[i], 0.0f) << i;
    EXPECT_EQ(mc.uncertainty[i], mc.aleatoric[i]) << i;
  }
}

TEST(McDropout, DropoutGivesEpistemicVarianceAndTotalIsTheSum) {
  field::Field field(SmallField(0.3), 4);
  const RenderedFrame a = RenderWith(field, 6);
  const RenderedFrame b = RenderWith(field, 6);
  EXPECT_EQ(a.uncertainty, b.uncertainty);  // masks are a pure function of the seed
  EXPECT_GT(*std::max_element(a.epistemic.begin(), a.epistemic.end()), 0.0f);
  for (int i = 0; i < 120; ++i) {
    EXPECT_GE(a.epistemic[i], 0.0f);
    // The ray score is linear in the variances, so the total's score is the sum of the parts' scores.
    EXPECT_NEAR(a.uncertainty[i], a.aleatoric[i] + a.epistemic[i], 1e-4f * (1 + a.uncertainty[i])) << i;
  }
}

}  // namespace
}  // namespace endorecon::render
