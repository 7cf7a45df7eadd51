// Depth bounds brought to the depth priors: loose ones tightened, cutting ones widened, the rest,
// and clips the priors cannot speak for, left as they are.
#include "worker/engine/scene/depth_bounds.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <vector>

namespace endorecon::scene {
namespace {

// Ten frames of 40 x 30 whose priors run evenly over [60, 105], bounded by near and far.
Clip ClipWithPriors(double near, double far, float scale = 1) {
  Clip clip;
  clip.width = 40;
  clip.height = 30;
  clip.near = near;
  clip.far = far;
  for (int f = 0; f < 10; ++f) {
    std::vector<float> depth(40 * 30);
    for (std::size_t i = 0; i < depth.size(); ++i)
      depth[i] = scale * float(60 + 45.0 * double(i) / depth.size());
    clip.depth.push_back(depth);
  }
  return clip;
}

TEST(DepthBoundsTest, LooseBoundsAreTightenedToThePriors) {
  Clip clip = ClipWithPriors(0, 1000);
  const std::string why = FitBoundsToPriors(clip);
  EXPECT_NEAR(clip.near, 60 - 0.25 * 45, 2.5);  // percentiles of a lattice of pixels
  EXPECT_NEAR(clip.far, 105 + 0.25 * 45, 2.5);
  EXPECT_NE(why.find("the depth bounds [0, 1000] are over twice as wide as the depth priors"),
            std::string::npos)
      << why;
}

TEST(DepthBoundsTest, BoundsThatCutThePriorsOffAreWidened) {
  Clip clip = ClipWithPriors(84, 86);
  const std::string why = FitBoundsToPriors(clip);
  EXPECT_NEAR(clip.near, 60 - 0.25 * 45, 2.5);  // percentiles of a lattice of pixels
  EXPECT_NEAR(clip.far, 105 + 0.25 * 45, 2.5);
  EXPECT_NE(why.find("[84, 86] cut off the depth priors"), std::string::npos) << why;
  EXPECT_NE(why.find("% of the priors lay outside the bounds"), std::string::npos) << why;
}

// A thin, far surface's noisy priors widen its bounds by a quarter of the priors' span, not of their
// depth (that made 81-89 into 62-114).
TEST(DepthBoundsTest, AThinFarSurfaceIsWidenedByItsOwnSpan) {
  Clip clip = ClipWithPriors(81, 89);
  for (auto& frame : clip.depth) {
    for (std::size_t i = 0; i < frame.size(); ++i) frame[i] = float(77 + 15.0 * double(i) / frame.size());
  }
  EXPECT_NE(FitBoundsToPriors(clip), "");
  EXPECT_NEAR(clip.near, 77 - 0.05 * 92, 1) << "a twentieth of the depth: more than a quarter of the span";
  EXPECT_NEAR(clip.far, 92 + 0.05 * 92, 1);
  // Priors of one value have no span: a twentieth of their depth each way.
  Clip flat = ClipWithPriors(40, 130);
  for (auto& frame : flat.depth) std::fill(frame.begin(), frame.end(), 85.0f);
  EXPECT_NE(FitBoundsToPriors(flat), "");
  EXPECT_NEAR(flat.near, 85 * 0.95, 1e-3);
  EXPECT_NEAR(flat.far, 85 * 1.05, 1e-3);
}

// A small clip is read densely enough to fit: four frames of 16 x 12 gave 12 priors at every 61st
// pixel, too few, and kept bounds that left the surface out of reach (black images, zero depth;
// found 2026-12-07).
TEST(DepthBoundsTest, ASmallClipsBoundsAreFittedToo) {
  Clip clip = ClipWithPriors(85, 85.01);
  clip.width = 16;
  clip.height = 12;
  clip.depth.resize(4);
  for (auto& frame : clip.depth) {
    frame.resize(16 * 12);
    for (std::size_t i = 0; i < frame.size(); ++i) frame[i] = float(60 + 45.0 * double(i) / frame.size());
  }
  EXPECT_NE(FitBoundsToPriors(clip).find("cut off the depth priors"), std::string::npos);
  EXPECT_NEAR(clip.near, 60 - 0.25 * 45, 1);
  EXPECT_NEAR(clip.far, 105 + 0.25 * 45, 1);
}

TEST(DepthBoundsTest, FittingBoundsAndOtherClipsAreLeftAlone) {
  Clip fitting = ClipWithPriors(50, 130);
  EXPECT_EQ(FitBoundsToPriors(fitting), "");
  EXPECT_EQ(fitting.near, 50);
  EXPECT_EQ(fitting.far, 130);
  Clip no_depth = ClipWithPriors(0, 1000);
  no_depth.depth.clear();
  EXPECT_EQ(FitBoundsToPriors(no_depth), "");
  Clip object = ClipWithPriors(0, 1000);
  object.object_radius = 1;
  EXPECT_EQ(FitBoundsToPriors(object), "");
  // Priors in other units than the poses (mm against m): a warning elsewhere, not new bounds.
  Clip units = ClipWithPriors(0.05, 0.2, 1000);
  EXPECT_EQ(FitBoundsToPriors(units), "");
  EXPECT_EQ(units.far, 0.2);
}

}  // namespace
}  // namespace endorecon::scene
