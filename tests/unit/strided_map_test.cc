// Maps rendered on every s-th pixel and row, brought back to every pixel: exact at the grid, linear
// between, the last grid value past the last grid row or column.
#include "worker/engine/eval/strided_map.h"

#include <gtest/gtest.h>

namespace endorecon::eval {
namespace {

TEST(StridedMap, PixelsAreTheGridRowByRow) {
  EXPECT_EQ(StridedPixels(5, 3, 2), (std::vector<int>{0, 2, 4, 10, 12, 14}));
  EXPECT_EQ(GridSize(5, 2), 3);
  EXPECT_EQ(GridSize(6, 4), 2);
  EXPECT_EQ(StridedPixels(4, 2, 1).size(), 8u);
}

TEST(StridedMap, StrideForKeepsTheGridWithinTheLimitAndGatherPicksThePixels) {
  EXPECT_EQ(StrideFor(160, 128, 20000, 2), 2);  // 80 x 64
  EXPECT_EQ(StrideFor(640, 512, 20000, 2), 5);  // 4: 160 x 128 = 20,480; 5: 128 x 103
  EXPECT_EQ(StrideFor(40, 30, 5000), 1);
  const std::vector<int> image{0, 1, 2, 10, 11, 12};  // 3 x 2, one channel
  EXPECT_EQ(Gather<int>(image, StridedPixels(3, 2, 2)), (std::vector<int>{0, 2}));
  const std::vector<int> rgb{0, 1, 2, 3, 4, 5};  // 2 pixels, three channels
  EXPECT_EQ(Gather<int>(rgb, {1}, 3), (std::vector<int>{3, 4, 5}));
  EXPECT_TRUE(Gather<int>(std::vector<int>{}, {0, 1}).empty()) << "no mask gives no mask";
}

TEST(StridedMap, UpsamplingReproducesALinearFunctionAndHoldsPastTheGrid) {
  const int w = 10, h = 7, stride = 4;  // grid columns 0, 4, 8; rows 0, 4
  const auto f = [](int x, int y) { return 0.5f + 0.25f * float(x) - 0.125f * float(y); };
  std::vector<float> grid;
  for (int p : StridedPixels(w, h, stride)) grid.push_back(f(p % w, p / w));
  const std::vector<float> up = UpsampleStrided(grid, w, h, stride);
  ASSERT_EQ(up.size(), std::size_t(w * h));
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const float expected = f(std::min(x, 8), std::min(y, 4));  // clamped past the last grid pixel
      EXPECT_NEAR(up[y * w + x], expected, 1e-5f) << x << "," << y;
    }
  }
}

}  // namespace
}  // namespace endorecon::eval
