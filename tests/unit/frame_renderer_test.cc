// FrameRenderer::Render with pixels to skip (outside a scope's view): they are left black, depth 0
// (unknown), opacity 0 and no uncertainty; the others are rendered as in the whole frame.
#include "worker/engine/render/frame_renderer.h"

#include <gtest/gtest.h>

#include "common/error.h"
#include "tests/unit/small_render_scene.h"
#include "worker/engine/scene/scene_box.h"

namespace endorecon::render {
namespace {

TEST(FrameRendererTest, SkippedPixelsAreLeftUnrenderedAndTheRestAsInTheWholeFrame) {
  const scene::Camera camera = testing::SmallCamera();
  field::Field field(testing::SmallField(0.0), 4);
  FrameRenderer renderer(field, scene::FrustumBox({camera}, 0.5, 2.0), testing::SmallRenderSettings(3));
  const RenderedFrame whole = renderer.Render(camera, 0.3f);
  std::vector<std::uint8_t> skip(120, 0);
  for (int p = 0; p < 120; ++p) skip[p] = (p % 12 < 3 || p / 12 >= 8) ? 1 : 0;  // a left band, the bottom
  const RenderedFrame part = renderer.Render(camera, 0.3f, skip);
  ASSERT_EQ(part.rgb.size(), whole.rgb.size());
  ASSERT_EQ(part.uncertainty.size(), whole.uncertainty.size());
  for (int p = 0; p < 120; ++p) {
    if (skip[p]) {
      for (int c = 0; c < 3; ++c) EXPECT_EQ(part.rgb[3 * p + c], 0.0f) << p;
      EXPECT_EQ(part.depth[p], 0.0f) << p;
      EXPECT_EQ(part.opacity[p], 0.0f) << p;
      EXPECT_EQ(part.uncertainty[p], 0.0f) << p;
      continue;
    }
    EXPECT_GT(whole.depth[p], 0.0f) << p;
    for (int c = 0; c < 3; ++c) EXPECT_FLOAT_EQ(part.rgb[3 * p + c], whole.rgb[3 * p + c]) << p;
    EXPECT_FLOAT_EQ(part.depth[p], whole.depth[p]) << p;
    EXPECT_FLOAT_EQ(part.aleatoric[p], whole.aleatoric[p]) << p;
  }
  // Nothing skipped: the whole frame, bit for bit.
  EXPECT_EQ(renderer.Render(camera, 0.3f, std::vector<std::uint8_t>(120, 0)).rgb, whole.rgb);
  EXPECT_THROW(renderer.Render(camera, 0.3f, std::vector<std::uint8_t>(7, 0)), Error);
}

}  // namespace
}  // namespace endorecon::render
