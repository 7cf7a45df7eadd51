#include "worker/engine/scene/transforms_loader.h"

#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <numbers>

#include "tests/unit/clip_fixture.h"
#include "tests/unit/temp_dir.h"

namespace endorecon::scene {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using testing::ErrorFrom;
using testing::Pattern;
using testing::TempDir;
using testing::WriteImage;

constexpr int kW = 8, kH = 6;

json Translation(double x, double y, double z) {
  return json::array({json::array({1, 0, 0, x}), json::array({0, 1, 0, y}), json::array({0, 0, 1, z}),
                      json::array({0, 0, 0, 1})});
}

class TransformsLoaderTest : public ::testing::Test {
 protected:
  // Static multi-view: three cameras 4 units from the origin, file paths without extension.
  void SetUp() override {
    transforms_ = {{"camera_angle_x", 2 * std::atan(0.5)}, {"frames", json::array()}};
    for (int i = 0; i < 3; ++i) {
      WriteImage(dir_ / "train" / ("r_" + std::to_string(i) + ".png"),
                 Pattern(kW, kH, CV_8UC3, [i](int x, int) { return x + i; }));
      transforms_["frames"].push_back({{"file_path", "./train/r_" + std::to_string(i)},
                                       {"transform_matrix", Translation(i - 1.0, 0, 4)}});
    }
  }
  Clip Load(const LoadOptions& options = {}) {
    testing::WriteBytes(dir_ / "transforms.json", transforms_.dump(1));
    return LoadTransformsClip(dir_.path(), options);
  }
  void ExpectError(const std::string& where, const std::string& what) {
    const std::string message = ErrorFrom([&] { Load(); });
    EXPECT_NE(message.find(where), std::string::npos) << message;
    EXPECT_NE(message.find(what), std::string::npos) << message;
  }
  json& Frame(int i) { return transforms_["frames"][i]; }

  TempDir dir_{"transforms"};
  json transforms_;
};

TEST_F(TransformsLoaderTest, LoadsStaticMultiView) {
  const Clip clip = Load();
  ASSERT_EQ(clip.frame_count(), 3);
  EXPECT_EQ(clip.width, kW);
  EXPECT_EQ(clip.height, kH);
  EXPECT_TRUE(clip.is_static);
  EXPECT_EQ(clip.times, std::vector<float>(3, 0.f));
  // camera_angle_x = 2 atan(1/2): fx = 0.5 W / tan(angle / 2) = W.
  EXPECT_NEAR(clip.cameras[0].fx, kW, 1e-12);
  EXPECT_NEAR(clip.cameras[0].fy, kW, 1e-12);
  EXPECT_EQ(clip.cameras[0].cx, 4);
  EXPECT_EQ(clip.cameras[0].cy, 3);
  EXPECT_TRUE(clip.cameras[2].c2w.col(3).isApprox(Eigen::Vector3d(1, 0, 4)));
  // No depth and no near/far: 0.05 and 2.5 x the median camera distance (sqrt(17), 4, sqrt(17)).
  EXPECT_NEAR(clip.near, 0.05 * std::sqrt(17.0), 1e-12);
  EXPECT_NEAR(clip.far, 2.5 * std::sqrt(17.0), 1e-12);
  EXPECT_FALSE(clip.has_depth());
  EXPECT_FALSE(clip.has_masks());
  EXPECT_EQ(clip.rgb[2][(0 * kW + 3) * 3 + 2], 5);  // blue = x + i
}

TEST_F(TransformsLoaderTest, LoadsMovingEndoscopeWithTimeDepthAndMasks) {
  transforms_.erase("camera_angle_x");
  transforms_.update({{"fl_x", 9.0},
                      {"fl_y", 9.5},
                      {"cx", 4.25},
                      {"cy", 2.75},
                      {"w", kW},
                      {"h", kH},
                      {"k1", 0.01},
                      {"depth_unit_scale_factor", 0.01}});
  for (int i = 0; i < 3; ++i) {
    WriteImage(dir_ / "depth" / (std::to_string(i) + ".png"),
               Pattern(kW, kH, CV_16UC1, [](int x, int) { return 5000 + 100 * x; }));
    WriteImage(dir_ / "mask" / (std::to_string(i) + ".png"),
               Pattern(kW, kH, CV_8UC1, [](int x, int) { return x == 7 ? 0 : 255; }));
    Frame(i)["time"] = 2.0 * i;  // seconds: rescaled to [0, 1]
    Frame(i)["depth_file_path"] = "depth/" + std::to_string(i) + ".png";
    Frame(i)["mask_path"] = "mask/" + std::to_string(i);
    Frame(i)["transform_matrix"] = Translation(0, 0, -0.5 * i);
  }
  Frame(1)["fl_x"] = 11.0;  // per-frame override
  const Clip clip = Load();
  EXPECT_FALSE(clip.is_static);
  EXPECT_EQ(clip.times, (std::vector<float>{0.f, 0.5f, 1.f}));
  EXPECT_EQ(clip.cameras[0].fx, 9.0);
  EXPECT_EQ(clip.cameras[1].fx, 11.0);
  EXPECT_EQ(clip.cameras[1].fy, 9.5);
  EXPECT_EQ(clip.cameras[2].cx, 4.25);
  EXPECT_EQ(clip.cameras[2].cy, 2.75);
  ASSERT_TRUE(clip.has_depth());
  EXPECT_FLOAT_EQ(clip.depth[1][2], 52.f);  // (5000 + 200) x 0.01
  ASSERT_TRUE(clip.has_masks());
  EXPECT_EQ(clip.tool_mask[0][7], 1);  // nerfstudio masks: 0 = excluded = tool
  EXPECT_EQ(clip.tool_mask[0][6], 0);
  // near/far from depth: 0.8 x 50 and 1.2 x 57.
  EXPECT_NEAR(clip.near, 40, 1e-4);
  EXPECT_NEAR(clip.far, 68.4, 1e-4);

  transforms_.update({{"near", 1.5}, {"far", 90}});
  const Clip bounded = Load();
  EXPECT_EQ(bounded.near, 1.5);
  EXPECT_EQ(bounded.far, 90);
}

TEST_F(TransformsLoaderTest, TimesInsideTheUnitIntervalAreKept) {
  for (int i = 0; i < 3; ++i) Frame(i)["time"] = 0.25 * i;
  LoadOptions options;
  EXPECT_EQ(Load(options).times, (std::vector<float>{0.f, 0.25f, 0.5f}));
  options.force_static = true;
  EXPECT_TRUE(Load(options).is_static);
}

TEST_F(TransformsLoaderTest, RejectsMissingImage) {
  Frame(1)["file_path"] = "train/missing";
  ExpectError("transforms.json frame 1", "also tried adding .png");
}

// A clip is its folder: a frame's file that lies outside it (an absolute path, or up through "..",
// even to a real image) is refused, so an uploaded clip cannot make a worker read files of its own.
TEST_F(TransformsLoaderTest, RejectsFilesOutsideTheClipsFolder) {
  const std::string inside = (dir_ / "train" / "r_0.png").string();
  ASSERT_TRUE(std::filesystem::is_regular_file(inside));
  std::filesystem::create_directories(dir_ / "sub");
  for (const std::string& path : {inside, std::string("../") + dir_.path().filename().string() + "/train/r_0",
                                  std::string("train/../../x/r_0.png"), std::string("/etc/passwd")}) {
    Frame(1)["file_path"] = path;
    ExpectError("transforms.json frame 1: file_path \"" + path + "\" leaves the clip's folder", "relative");
  }
  Frame(1)["file_path"] = "sub/../train/r_1";  // up and down again, inside: fine
  EXPECT_EQ(Load({}).frame_count(), 3);
  Frame(1)["file_path"] = "sub";
  ExpectError("transforms.json frame 1: file_path", "is not a regular file");
  Frame(1)["file_path"] = "";
  ExpectError("transforms.json frame 1: \"file_path\" is empty", "");
  // A NUL cut the message at it (found 2026-12-06): the name is shown escaped, and what is wrong said.
  Frame(1)["file_path"] = std::string("./train/r_1\0.png", 16);
  ExpectError("transforms.json frame 1: \"file_path\" \"./train/r_1\\u0000.png\" holds a control character",
              "NUL");
}

// A declared size over the limit is blamed on transforms.json's "w" and "h", not on the images.
TEST_F(TransformsLoaderTest, ADeclaredSizeOverTheLimitNamesItsKeys) {
  transforms_["w"] = 64000;
  transforms_["h"] = 48000;
  const std::string message = ErrorFrom([&] { Load(); }, ErrorCode::kInvalidArgument);
  EXPECT_NE(message.find("transforms.json frame 0: \"w\" x \"h\": frames of 64000x48000"), std::string::npos)
      << message;
}

// Times too far apart to rescale once became NaN, and training "diverged" at its first step.
TEST_F(TransformsLoaderTest, RejectsTimesTooFarApartToRescale) {
  for (int i = 0; i < 3; ++i) Frame(i)["time"] = (i - 1) * 1e308;
  ExpectError("transforms.json: the frames' times span", "too wide to rescale to [0, 1]");
}

TEST_F(TransformsLoaderTest, RejectsMissingTransformsFile) {
  const std::string message = ErrorFrom([&] { LoadTransformsClip(dir_.path(), {}); });
  EXPECT_NE(message.find("transforms.json: cannot open"), std::string::npos) << message;
}

TEST_F(TransformsLoaderTest, RejectsInvalidJson) {
  testing::WriteBytes(dir_ / "transforms.json", "{\"frames\": [");
  const std::string message = ErrorFrom([&] { LoadTransformsClip(dir_.path(), {}); });
  EXPECT_NE(message.find("not valid JSON"), std::string::npos) << message;
}

TEST_F(TransformsLoaderTest, RejectsZeroFrames) {
  transforms_["frames"] = json::array();
  ExpectError("transforms.json", "zero frames");
}

TEST_F(TransformsLoaderTest, RejectsSomeFramesWithoutTime) {
  Frame(0)["time"] = 0.0;
  Frame(2)["time"] = 1.0;
  ExpectError("transforms.json frame 1", "no \"time\" while 2 of 3 frames have one");
}

TEST_F(TransformsLoaderTest, RejectsPartialDepth) {
  WriteImage(dir_ / "d.png", Pattern(kW, kH, CV_8UC1, [](int, int) { return 9; }));
  Frame(0)["depth_file_path"] = "d.png";
  ExpectError("frame 1", "has no depth file while frame 0 has one");
}

TEST_F(TransformsLoaderTest, RejectsUnequalSizes) {
  WriteImage(dir_ / "train" / "r_2.png", Pattern(kW + 2, kH, CV_8UC3, [](int, int) { return 1; }));
  ExpectError("r_2.png", "size 10x6 differs from the clip's 8x6");
}

TEST_F(TransformsLoaderTest, RejectsDeclaredSizesThatDisagree) {
  Frame(0).update({{"w", 8}, {"h", 6}});
  Frame(2).update({{"w", 8}, {"h", 5}});
  ExpectError("transforms.json frame 2", "size 8x5 differs from the clip's 8x6");
}

TEST_F(TransformsLoaderTest, RejectsMissingOrMalformedTransform) {
  Frame(1).erase("transform_matrix");
  ExpectError("transforms.json frame 1", "no \"transform_matrix\"");
  Frame(1)["transform_matrix"] = json::array({json::array({1, 0, 0})});
  ExpectError("transforms.json frame 1", "must be 4x4 numbers");
  Frame(1)["transform_matrix"] = Translation(0, 0, 1);
  Frame(1)["transform_matrix"][3][0] = 0.5;
  ExpectError("transforms.json frame 1", "last row of \"transform_matrix\" must be [0, 0, 0, 1]");
}

TEST_F(TransformsLoaderTest, RejectsDegeneratePose) {
  Frame(2)["transform_matrix"][0][0] = 2.0;
  ExpectError("transforms.json frame 2", "not orthonormal");
  Frame(2)["transform_matrix"] = Translation(0, 0, 1);
  Frame(2)["transform_matrix"][2][2] = -1;
  ExpectError("transforms.json frame 2", "determinant -1");
}

TEST_F(TransformsLoaderTest, RejectsMissingOrNonPositiveFocalLength) {
  transforms_.erase("camera_angle_x");
  ExpectError("transforms.json frame 0", "no focal length");
  transforms_["fl_x"] = -3.0;
  ExpectError("transforms.json frame 0", "focal length must be finite and positive (fx = -3");
  transforms_["fl_x"] = "ten";
  ExpectError("transforms.json", "\"fl_x\" must be a finite number, found \"ten\"");
}

// A field of view of pi or more is no pinhole camera's (pi gave fx = 1e-14, accepted until
// 2026-12-05), one in degrees is named as such, and a focal length can be too short for the frame.
TEST_F(TransformsLoaderTest, RejectsAFieldOfViewNoPinholeCameraHas) {
  transforms_["camera_angle_x"] = std::numbers::pi;
  ExpectError("transforms.json frame 0", "\"camera_angle_x\" must be an angle in radians between 0 and pi");
  transforms_["camera_angle_x"] = 60;
  ExpectError("transforms.json frame 0", "found 60 (degrees?)");
  transforms_["camera_angle_x"] = 3.1;
  ExpectError("transforms.json frame 0", "field of view of 177.6");
  transforms_.erase("camera_angle_x");
  transforms_["fl_x"] = 0.01;  // 8 px across
  ExpectError("transforms.json frame 0", "more than 170 (a pinhole camera's");
  transforms_["fl_x"] = 1.0;  // 152 degrees across 8 px: wide, and a pinhole's
  EXPECT_EQ(Load().frame_count(), 3);
}

// cx = 5000 in a 96-pixel frame and fy = 1000 fx trained without a word (found 2026-12-05).
TEST_F(TransformsLoaderTest, RejectsAPrincipalPointOutsideTheFrameAndPixelsOfNoCamera) {
  transforms_["cx"] = 5000;
  ExpectError("transforms.json frame 0", "the principal point (cx = 5000, cy = ");
  transforms_["cx"] = -1e6;
  ExpectError("transforms.json frame 0", "lies outside the");
  transforms_.erase("cx");
  transforms_.erase("camera_angle_x");
  transforms_["fl_x"] = 10.0;
  transforms_["fl_y"] = 10000.0;
  ExpectError("transforms.json frame 0", "fy / fx is 1000");
  transforms_["fl_y"] = 15.0;  // 1.5: an anamorphic lens's
  EXPECT_EQ(Load().frame_count(), 3);
}

// A fisheye's pixels map to rays another way: ignored without a word until 2026-12-05.
TEST_F(TransformsLoaderTest, RejectsACameraModelThatIsNoPinhole) {
  transforms_["camera_model"] = "OPENCV";
  EXPECT_EQ(Load().frame_count(), 3);
  transforms_["camera_model"] = "OPENCV_FISHEYE";
  ExpectError("transforms.json", "\"camera_model\" OPENCV_FISHEYE is not a pinhole camera's");
}

TEST_F(TransformsLoaderTest, RejectsNearNotBelowFar) {
  transforms_.update({{"near", 5}, {"far", 5}});
  ExpectError("transforms.json", "0 <= near < far (near = 5, far = 5)");
}

TEST_F(TransformsLoaderTest, RejectsUnderivableBounds) {
  for (int i = 0; i < 3; ++i) Frame(i)["transform_matrix"] = Translation(0, 0, 0);
  ExpectError("transforms.json", "cannot derive near and far");
}

TEST_F(TransformsLoaderTest, RejectsMaskWithOtherValues) {
  for (int i = 0; i < 3; ++i) {
    WriteImage(dir_ / "m.png", Pattern(kW, kH, CV_8UC1, [](int x, int) { return x * 30; }));
    Frame(i)["mask_path"] = "m.png";
  }
  ExpectError("m.png", "found values {0, 30, 60, 90, 120, 150, 180, 210}");
}

}  // namespace
}  // namespace endorecon::scene
