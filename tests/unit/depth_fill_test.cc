// Holes in a depth prior filled from their surroundings (train/depth_fill.h).
#include "worker/engine/train/depth_fill.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "common/error.h"

namespace endorecon::train {
namespace {

constexpr int kW = 40, kH = 30;

int Pixel(int x, int y) { return y * kW + x; }

// A tilted plane, z = 50 + 0.2 x + 0.1 y, measured everywhere.
std::vector<float> Plane() {
  std::vector<float> depth(kW * kH);
  for (int y = 0; y < kH; ++y) {
    for (int x = 0; x < kW; ++x) depth[Pixel(x, y)] = 50.0f + 0.2f * x + 0.1f * y;
  }
  return depth;
}

TEST(FillDepthHolesTest, AHighlightsHoleTakesThePlaneAroundIt) {
  const std::vector<float> plane = Plane();
  std::vector<float> depth = plane;
  for (int y = 12; y < 16; ++y) {
    for (int x = 18; x < 23; ++x) depth[Pixel(x, y)] = 0.0f;  // 4 x 5 pixels, as a highlight leaves
  }
  depth[Pixel(5, 5)] = std::numeric_limits<float>::quiet_NaN();  // not finite: a hole too
  const FilledDepth filled = FillDepthHoles(depth, {}, kW, kH, 2.0);
  EXPECT_EQ(filled.filled, 21u);
  EXPECT_EQ(filled.left, 0u);
  for (int p = 0; p < kW * kH; ++p) {
    if (depth[p] > 0) {
      EXPECT_EQ(filled.depth[p], depth[p]) << p;  // measured pixels stay as they were
    } else {
      // The measured pixels around a hole's edge lie mostly on one side: the mean is taken about a
      // point up to a pixel or so off, 0.2 a pixel on this plane.
      EXPECT_NEAR(filled.depth[p], plane[p], 0.3) << p;
    }
  }
}

TEST(FillDepthHolesTest, HolesByTheToolOrFarFromAnyMeasurementStay) {
  std::vector<float> depth = Plane();
  std::vector<std::uint8_t> tool(kW * kH, 0);
  for (int y = 0; y < kH; ++y) {
    for (int x = 0; x < 8; ++x) tool[Pixel(x, y)] = 1;  // the tool over the left edge
  }
  depth[Pixel(9, 10)] = 0.0f;  // 2 pixels from the tool: where depth jumps from tool to tissue
  for (int y = 0; y < kH; ++y) {
    for (int x = 25; x < kW; ++x) depth[Pixel(x, y)] = 0.0f;  // a band 15 pixels wide, no measurement
  }
  const FilledDepth filled = FillDepthHoles(depth, tool, kW, kH, 2.0);
  EXPECT_EQ(filled.depth[Pixel(9, 10)], 0.0f);
  EXPECT_GT(filled.depth[Pixel(25, 10)], 0.0f);  // the band's edge is filled
  EXPECT_EQ(filled.depth[Pixel(35, 10)], 0.0f);  // its middle is too far from anything measured
  EXPECT_GT(filled.filled, 0u);
  EXPECT_GT(filled.left, 0u);
  EXPECT_EQ(filled.filled + filled.left, std::size_t(1 + 15 * kH));
  // sigma 0 fills nothing.
  const FilledDepth none = FillDepthHoles(depth, tool, kW, kH, 0.0);
  EXPECT_EQ(none.filled, 0u);
  EXPECT_EQ(none.depth, depth);
}

TEST(FillDepthHolesTest, SizesThatDisagreeAreRefused) {
  const std::vector<float> depth = Plane();
  EXPECT_THROW(FillDepthHoles(depth, {}, kW + 1, kH, 2.0), Error);
  EXPECT_THROW(FillDepthHoles(depth, std::vector<std::uint8_t>(5), kW, kH, 2.0), Error);
  EXPECT_THROW(FillDepthHoles(depth, {}, kW, kH, -1.0), Error);
}

}  // namespace
}  // namespace endorecon::train
