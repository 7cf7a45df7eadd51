#include "worker/engine/eval/pixel_error.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <vector>

#include "common/error.h"

namespace endorecon::eval {
namespace {

TEST(PixelError, RmseOverChannelsPerPixel) {
  const std::vector<std::uint8_t> reference = {0, 0, 0, 255, 255, 255};
  const std::vector<float> rendered = {0.3f, 0.0f, 0.4f, 2.0f, 1.0f, 1.0f};  // 2.0 clamps to 1
  const std::vector<float> error = PixelRmse(rendered, reference, 2, 1);
  ASSERT_EQ(error.size(), 2u);
  EXPECT_NEAR(error[0], std::sqrt((0.09 + 0.16) / 3), 1e-6);
  EXPECT_EQ(error[1], 0.0f);
  EXPECT_THROW(PixelRmse(rendered, reference, 3, 1), Error);
}

}  // namespace
}  // namespace endorecon::eval
