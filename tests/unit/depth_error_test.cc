#include "worker/engine/eval/depth_error.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <vector>

#include "common/error.h"

namespace endorecon::eval {
namespace {

constexpr int kW = 8, kH = 4;

TEST(DepthError, KnownOffsetsGiveClosedForms) {
  std::vector<float> gt(kW * kH, 2.0f), depth(kW * kH);
  for (int p = 0; p < kW * kH; ++p) depth[p] = p % 2 == 0 ? 2.3f : 1.9f;
  const DepthError e = MeasureDepth(depth, gt, {}, kW, kH, 1.0, 6.0);
  EXPECT_NEAR(e.rmse, std::sqrt((0.09 + 0.01) / 2), 1e-6);
  EXPECT_NEAR(e.mae, 0.2, 1e-6);
  EXPECT_NEAR(e.rmse_relative, std::sqrt(0.05) / 5.0, 1e-6);
  EXPECT_EQ(e.valid_pixels, kW * kH);
}

TEST(DepthError, ToolPixelsAndUnknownDepthAreLeftOut) {
  std::vector<float> gt(kW * kH, 2.0f), depth(kW * kH, 2.1f);
  std::vector<std::uint8_t> mask(kW * kH, 0);
  depth[0] = 50.0f;
  mask[0] = 1;
  depth[1] = 50.0f;
  gt[1] = 0.0f;
  depth[2] = 50.0f;
  gt[2] = std::nanf("");
  const DepthError e = MeasureDepth(depth, gt, mask, kW, kH, 0.0, 4.0);
  EXPECT_NEAR(e.rmse, 0.1, 1e-6);
  EXPECT_EQ(e.valid_pixels, kW * kH - 3);
}

TEST(DepthError, NoValidPixelIsUndefinedAndSerialisesAsNull) {
  const std::vector<float> gt(kW * kH, 0.0f), depth(kW * kH, 1.0f);
  const DepthError e = MeasureDepth(depth, gt, {}, kW, kH, 0.0, 4.0);
  EXPECT_TRUE(std::isnan(e.rmse));
  EXPECT_EQ(e.valid_pixels, 0);
  EXPECT_TRUE(nlohmann::json::parse(ToJson(e).dump())["rmse"].is_null());
}

TEST(DepthError, NonFiniteRenderedDepthIsAnError) {
  const std::vector<float> gt(kW * kH, 2.0f);
  std::vector<float> depth(kW * kH, 2.0f);
  depth[3] = std::numeric_limits<float>::infinity();
  EXPECT_FALSE(std::isfinite(MeasureDepth(depth, gt, {}, kW, kH, 0.0, 4.0).rmse));
}

TEST(DepthError, EmptyDepthRangeThrows) {
  const std::vector<float> gt(kW * kH, 2.0f);
  EXPECT_THROW(MeasureDepth(gt, gt, {}, kW, kH, 3.0, 3.0), Error);
}

TEST(DepthError, FramesSerialiseWithSummary) {
  const std::vector<DepthError> frames = {{0.1, 0.05, 0.01, 10}, {0.3, 0.15, 0.03, 12}};
  const nlohmann::json j = ToJson(frames);
  EXPECT_NEAR(j["rmse"]["mean"].get<double>(), 0.2, 1e-12);
  EXPECT_NEAR(j["rmse_relative"]["std"].get<double>(), 0.01, 1e-12);
  EXPECT_EQ(j["per_frame"].size(), 2u);
  EXPECT_EQ(j["per_frame"][1]["valid_pixels"].get<long>(), 12);
}

}  // namespace
}  // namespace endorecon::eval
