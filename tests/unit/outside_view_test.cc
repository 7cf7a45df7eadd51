// The part of an endoscope's frames outside its round view: dark in every frame and reaching the
// frame's edge; left out of every frame's masks without counting as occlusion.
#include "worker/engine/scene/outside_view.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "common/error.h"
#include "worker/engine/train/ray_sampler.h"

namespace endorecon::scene {
namespace {

constexpr int kW = 40, kH = 30;

bool InView(int x, int y) { return std::hypot(x - 19.5, y - 14.5) < 14; }
bool InHole(int x, int y) { return std::abs(x - 20) <= 1 && std::abs(y - 15) <= 1; }

// Three frames of a round view: tissue (60-200, changing) inside, black with a little noise (0-5)
// outside, a hole inside the view as dark as the outside, and one outside pixel (0, 0) lit once.
Clip RoundView() {
  Clip clip;
  clip.source = "round";
  clip.width = kW;
  clip.height = kH;
  clip.cameras.resize(3);
  clip.times = {0, 0.5f, 1};
  for (int f = 0; f < 3; ++f) {
    std::vector<std::uint8_t> rgb(3 * kW * kH);
    for (int y = 0; y < kH; ++y) {
      for (int x = 0; x < kW; ++x) {
        for (int c = 0; c < 3; ++c) {
          const int noise = (x * 7 + y * 13 + c * 5 + f * 3) % 6;
          rgb[3 * (y * kW + x) + c] =
              std::uint8_t(InView(x, y) && !InHole(x, y) ? 60 + (x * 11 + y * 3 + f * 17 + c) % 140 : noise);
        }
      }
    }
    if (f == 1) rgb[1] = 40;  // pixel (0, 0), green, once
    clip.rgb.push_back(std::move(rgb));
  }
  return clip;
}

TEST(OutsideViewTest, TheDarkCornersButNotADarkHoleInsideNorAPixelLitOnce) {
  const Clip clip = RoundView();
  const std::vector<std::uint8_t> mask = OutsideViewMask(clip, 8);
  ASSERT_EQ(mask.size(), std::size_t(kW * kH));
  for (int y = 0; y < kH; ++y) {
    for (int x = 0; x < kW; ++x) {
      const bool outside = !InView(x, y) && !(x == 0 && y == 0);
      EXPECT_EQ(mask[y * kW + x], outside ? 1 : 0) << x << "," << y;
    }
  }
  // The noise reaches 5: at level 4 only part of the outside is dark in every frame.
  const std::vector<std::uint8_t> strict = OutsideViewMask(clip, 4);
  EXPECT_LT(std::count(strict.begin(), strict.end(), 1), std::count(mask.begin(), mask.end(), 1));
}

TEST(OutsideViewTest, NoneWhereNothingStaysDark) {
  Clip clip = RoundView();
  for (auto& frame : clip.rgb) {
    for (auto& v : frame) v = std::uint8_t(v + 9);  // every pixel above 8 in every frame
  }
  EXPECT_TRUE(OutsideViewMask(clip, 8).empty());
  EXPECT_TRUE(OutsideViewMask(Clip{}, 8).empty());
  // All black: no view to keep, nothing left out.
  for (auto& frame : clip.rgb) std::fill(frame.begin(), frame.end(), 0);
  EXPECT_TRUE(OutsideViewMask(clip, 8).empty());
}

TEST(OutsideViewTest, ExcludedFromEveryFramesMasksWithoutCountingAsOcclusion) {
  Clip clip = RoundView();
  const std::vector<std::uint8_t> mask = OutsideViewMask(clip, 8);
  // Without masks: made, the outside only.
  Clip plain = clip;
  ExcludeFromFrames(plain, mask);
  ASSERT_EQ(plain.tool_mask.size(), 3u);
  for (const auto& frame : plain.tool_mask) EXPECT_EQ(frame, mask);
  EXPECT_TRUE(plain.eval_mask.empty());
  EXPECT_EQ(plain.outside_view, mask);
  // With tool and evaluation masks: added to them, their tool pixels kept.
  const int tool = 15 * kW + 10;  // inside the view
  clip.tool_mask.assign(3, std::vector<std::uint8_t>(kW * kH, 0));
  clip.tool_mask[0][tool] = 1;
  clip.eval_mask = clip.tool_mask;
  ExcludeFromFrames(clip, mask);
  for (auto* masks : {&clip.tool_mask, &clip.eval_mask}) {
    for (int f = 0; f < 3; ++f) {
      for (int p = 0; p < kW * kH; ++p) {
        EXPECT_EQ((*masks)[f][p], (mask[p] || (f == 0 && p == tool)) ? 1 : 0) << f << " " << p;
      }
    }
  }
  // The ray sampler weighs the tool pixel against the most-occluded tissue pixel (itself, once: 2x),
  // not against the outside, masked in all three frames (it would be 1 + 1/3).
  const train::RaySampler sampler(clip, {0, 1, 2});
  EXPECT_FLOAT_EQ(sampler.Weight(1, tool), 2.0f);
  EXPECT_FLOAT_EQ(sampler.Weight(1, 15 * kW + 20 + 3), 1.0f);
  EXPECT_FLOAT_EQ(sampler.Weight(1, 0 * kW + 1), 0.0f) << "outside the view: never drawn";
}

TEST(OutsideViewTest, AMaskOfTheWrongSizeIsRefused) {
  Clip clip = RoundView();
  EXPECT_THROW(ExcludeFromFrames(clip, std::vector<std::uint8_t>(10, 1)), Error);
}

}  // namespace
}  // namespace endorecon::scene
