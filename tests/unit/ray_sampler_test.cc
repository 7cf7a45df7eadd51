#include "worker/engine/train/ray_sampler.h"

#include <gtest/gtest.h>

#include "common/error.h"

namespace endorecon::train {
namespace {

scene::Clip MaskedClip() {
  scene::Clip clip;
  clip.width = 4;
  clip.height = 1;
  clip.cameras.resize(2);
  clip.times = {0, 1};
  clip.rgb.assign(2, std::vector<std::uint8_t>(12, 0));
  // Pixel 0 is tool in frame 0; pixel 1 is tool in both frames; pixels 2, 3 never.
  clip.tool_mask = {{1, 1, 0, 0}, {0, 1, 0, 0}};
  return clip;
}

TEST(RaySamplerTest, NeverPicksToolAndFavoursOftenOccludedTissue) {
  const scene::Clip clip = MaskedClip();
  RaySampler sampler(clip, {0, 1});
  int counts[2][4] = {};
  for (int i = 0; i < 40000; ++i) {
    const RayPick pick = sampler.Pick(1, std::uint64_t(i));
    ASSERT_EQ(clip.tool_mask[pick.frame][pick.pixel], 0) << "picked a tool pixel";
    ++counts[pick.frame][pick.pixel];
  }
  // Frame 1 pixel 0 was tool once out of the most (2): weight 1.5 against 1 for pixels 2 and 3.
  EXPECT_NEAR(double(counts[1][0]) / counts[1][2], 1.5, 0.12);
  EXPECT_NEAR(double(counts[1][3]) / counts[1][2], 1.0, 0.1);
}

TEST(RaySamplerTest, AllToolClipIsAnError) {
  scene::Clip clip = MaskedClip();
  clip.tool_mask = {{1, 1, 1, 1}, {1, 1, 1, 1}};
  EXPECT_THROW(RaySampler(clip, {0, 1}), Error);
}

TEST(RaySamplerTest, PicksArePureFunctionsOfSeedAndStream) {
  const scene::Clip clip = MaskedClip();
  RaySampler sampler(clip, {0, 1});
  for (int i = 0; i < 100; ++i) {
    const RayPick a = sampler.Pick(9, std::uint64_t(i)), b = sampler.Pick(9, std::uint64_t(i));
    EXPECT_EQ(a.frame, b.frame);
    EXPECT_EQ(a.pixel, b.pixel);
  }
}

}  // namespace
}  // namespace endorecon::train
