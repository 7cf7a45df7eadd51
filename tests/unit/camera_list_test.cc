#include "worker/engine/scene/camera_list.h"

#include <gtest/gtest.h>

#include "common/error.h"
#include "tests/unit/clip_fixture.h"
#include "tests/unit/temp_dir.h"

namespace endorecon::scene {
namespace {

const char* kGood = R"({"fl_x": 100, "w": 64, "h": 48, "frames": [
  {"transform_matrix": [[1,0,0,5],[0,1,0,0],[0,0,1,0],[0,0,0,1]], "time": 0.25},
  {"transform_matrix": [[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]], "fl_x": 50, "cx": 10, "time": 0}]})";

std::string ErrorOf(const std::string& text) {
  testing::TempDir dir("cameras");
  testing::WriteBytes(dir / "cameras.json", text);
  try {
    ReadCameraList(dir / "cameras.json");
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
    return e.what();
  }
  return "";
}

TEST(CameraListTest, ReadsIntrinsicsPosesAndTimes) {
  testing::TempDir dir("cameras");
  testing::WriteBytes(dir / "cameras.json", kGood);
  const auto cameras = ReadCameraList(dir / "cameras.json");
  ASSERT_EQ(cameras.size(), 2u);
  EXPECT_FLOAT_EQ(cameras[0].time, 0.25f);
  EXPECT_EQ(cameras[0].camera.width, 64);
  EXPECT_DOUBLE_EQ(cameras[0].camera.fx, 100);
  EXPECT_DOUBLE_EQ(cameras[0].camera.cy, 24);
  EXPECT_DOUBLE_EQ(cameras[0].camera.c2w(0, 3), 5);
  EXPECT_DOUBLE_EQ(cameras[1].camera.fx, 50) << "a per-frame focal length overrides the top level";
  EXPECT_DOUBLE_EQ(cameras[1].camera.cx, 10);
  EXPECT_FLOAT_EQ(cameras[1].time, 0.0f);
}

TEST(CameraListTest, BadFormsNameTheFrameAndField) {
  EXPECT_NE(ErrorOf("[]").find("frames"), std::string::npos);
  EXPECT_NE(ErrorOf(R"({"fl_x": 1, "frames": [{"transform_matrix": [[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]}]})")
                .find("\"w\""),
            std::string::npos);
  EXPECT_NE(ErrorOf(R"({"w": 8, "h": 8, "frames": [{"transform_matrix": [[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]}]})")
                .find("focal"),
            std::string::npos);
  EXPECT_NE(ErrorOf(R"({"fl_x": 1, "w": 8, "h": 8, "frames": [{"transform_matrix": [[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]], "time": 2}]})")
                .find("frame 0"),
            std::string::npos);
  EXPECT_NE(ErrorOf(R"({"fl_x": 1, "w": 8, "h": 8, "frames": [{"transform_matrix": [[2,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]}]})"),
            "");
  EXPECT_NE(ErrorOf("{not json"), "");
}

// Every view has a time or none has (a static scene's, at t = 0); a top-level "time" is every view's.
// A list timing only some rendered the others at t = 0 without a word until 2026-12-05.
TEST(CameraListTest, EveryViewHasItsTimeOrNoneHas) {
  const std::string mixed = ErrorOf(
      R"({"fl_x": 10, "w": 8, "h": 8, "frames": [{"transform_matrix": [[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]},
      {"transform_matrix": [[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]], "time": 0.5}]})");
  EXPECT_NE(mixed.find("frame 1 has a \"time\" and frame 0 has none"), std::string::npos) << mixed;
  testing::TempDir dir("cameras");
  testing::WriteBytes(dir / "cameras.json",
                      R"({"fl_x": 10, "w": 8, "h": 8, "time": 0.75, "frames": [
      {"transform_matrix": [[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]},
      {"transform_matrix": [[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]], "time": 0.5}]})");
  const auto cameras = ReadCameraList(dir / "cameras.json");
  EXPECT_FLOAT_EQ(cameras[0].time, 0.75f);
  EXPECT_FLOAT_EQ(cameras[1].time, 0.5f);
}

// A view larger than a clip's frames may be is refused before anything is allocated for it.
TEST(CameraListTest, AViewLargerThanAFrameMayBeIsRefused) {
  for (const char* size : {R"("w": 100000, "h": 100000)", R"("w": 1e300, "h": 8)"}) {
    testing::TempDir dir("cameras");
    testing::WriteBytes(
        dir / "cameras.json",
        std::string(R"({"fl_x": 1, )") + size +
            R"(, "frames": [{"transform_matrix": [[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]}]})");
    const std::string message =
        testing::ErrorFrom([&] { ReadCameraList(dir / "cameras.json"); }, ErrorCode::kInvalidArgument);
    EXPECT_NE(message.find("frame 0: \"w\" x \"h\""), std::string::npos) << message;
    EXPECT_NE(message.find("exceed the limit of 16777216 pixels per frame"), std::string::npos) << message;
  }
}

}  // namespace
}  // namespace endorecon::scene
