#include "worker/engine/scene/endonerf_loader.h"

#include <gtest/gtest.h>
#include <spdlog/sinks/ostream_sink.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <sstream>

#include "tests/unit/clip_fixture.h"
#include "tests/unit/temp_dir.h"
#include "worker/engine/scene/clip_loader.h"

namespace endorecon::scene {
namespace {

namespace fs = std::filesystem;
using testing::ErrorFrom;
using testing::Pattern;
using testing::PoseRow;
using testing::TempDir;
using testing::WriteImage;
using testing::WritePoses;

constexpr int kW = 8, kH = 6, kFrames = 3;

std::string Name(int i) { return "frame-00" + std::to_string(i) + ".png"; }

// A valid 3-frame clip of 8x6 frames: colour, 8-bit depth 10 + x, masks with the tool at x >= 6.
class EndoNerfLoaderTest : public ::testing::Test {
 protected:
  void SetUp() override {
    for (int i = 0; i < kFrames; ++i) {
      WriteImage(dir_ / "images" / Name(i),
                 Pattern(kW, kH, CV_8UC3, [i](int x, int y) { return 10 * x + y + i; }));
      WriteImage(dir_ / "depth" / Name(i), Pattern(kW, kH, CV_8UC1, [](int x, int) { return 10 + x; }));
      WriteImage(dir_ / "masks" / Name(i),
                 Pattern(kW, kH, CV_8UC1, [](int x, int) { return x >= 6 ? 255 : 0; }));
    }
    rows_.assign(kFrames, PoseRow{});
    for (int i = 0; i < kFrames; ++i) {
      rows_[i].near = 2 + i;
      rows_[i].far = 30 - i;
    }
    WritePoses(dir_ / "poses_bounds.npy", rows_);
  }
  Clip Load(const LoadOptions& options = {}) { return LoadEndoNerfClip(dir_.path(), options); }
  std::string LoadError(ErrorCode code = ErrorCode::kInvalidArgument) {
    return ErrorFrom([&] { Load(); }, code);
  }
  void ExpectError(const std::string& file, const std::string& what) {
    const std::string message = LoadError();
    EXPECT_NE(message.find(file), std::string::npos) << message;
    EXPECT_NE(message.find(what), std::string::npos) << message;
  }

  TempDir dir_{"endonerf"};
  std::vector<PoseRow> rows_;
};

TEST_F(EndoNerfLoaderTest, LoadsFramesCamerasAndBounds) {
  const Clip clip = Load();
  ASSERT_EQ(clip.frame_count(), kFrames);
  EXPECT_EQ(clip.width, kW);
  EXPECT_EQ(clip.height, kH);
  EXPECT_EQ(clip.near, 2);
  EXPECT_EQ(clip.far, 30);
  EXPECT_EQ(clip.times, (std::vector<float>{0.f, 0.5f, 1.f}));
  EXPECT_FALSE(clip.is_static);
  // LLFF [down, right, back] identity becomes OpenGL c2w = [right, up, back] = [e_y, -e_x, e_z].
  Eigen::Matrix<double, 3, 4> expected;
  expected << 0, -1, 0, 0, 1, 0, 0, 0, 0, 0, 1, 0;
  EXPECT_TRUE(clip.cameras[1].c2w.isApprox(expected)) << clip.cameras[1].c2w;
  EXPECT_EQ(clip.cameras[0].fx, 10);
  EXPECT_EQ(clip.cameras[0].fy, 10);
  EXPECT_EQ(clip.cameras[0].cx, 4);
  EXPECT_EQ(clip.cameras[0].cy, 3);
  // Pixel (x=2, y=1) of frame 2: B = 10x + y + i = 23, G = 11, R = 7, stored as RGB.
  const std::size_t at = (1 * kW + 2) * 3;
  EXPECT_EQ(clip.rgb[2][at + 0], 7);
  EXPECT_EQ(clip.rgb[2][at + 1], 11);
  EXPECT_EQ(clip.rgb[2][at + 2], 23);
  ASSERT_TRUE(clip.has_depth());
  EXPECT_EQ(clip.depth[0][1 * kW + 5], 15.f);
  ASSERT_TRUE(clip.has_masks());
  EXPECT_EQ(clip.tool_mask[0][7], 1);
  EXPECT_EQ(clip.tool_mask[0][5], 0);
  EXPECT_TRUE(clip.eval_mask.empty());
  EXPECT_FALSE(clip.has_stereo());
  EXPECT_TRUE(clip.gt_rgb.empty());
}

TEST_F(EndoNerfLoaderTest, DepthAndMasksAreOptional) {
  fs::remove_all(dir_ / "depth");
  fs::remove_all(dir_ / "masks");
  const Clip clip = Load();
  EXPECT_FALSE(clip.has_depth());
  EXPECT_FALSE(clip.has_masks());
}

// Zero is "not measured": depth maps that are all zero everywhere (an exporter's placeholder) are no
// depth, and the clip loads as one without depth files; one all-zero frame among measured ones stays.
TEST_F(EndoNerfLoaderTest, DepthMapsAllZeroAreNoDepth) {
  for (int i = 0; i < kFrames; ++i)
    WriteImage(dir_ / "depth" / Name(i), Pattern(kW, kH, CV_8UC1, [](int, int) { return 0; }));
  EXPECT_FALSE(Load().has_depth());
  WriteImage(dir_ / "depth" / Name(2), Pattern(kW, kH, CV_8UC1, [](int x, int) { return x == 3 ? 20 : 0; }));
  const Clip clip = Load();
  ASSERT_TRUE(clip.has_depth());
  EXPECT_EQ(clip.depth[0][3], 0.f);
  EXPECT_EQ(clip.depth[2][3], 20.f);
}

// Poses far from the origin load, with a warning that the results' float coordinates are coarse
// there (1e9 from the origin: steps of ~119 units against a depth range of 28).
TEST_F(EndoNerfLoaderTest, PosesFarFromTheOriginLoadWithAWarningOfCoarseResults) {
  for (auto& row : rows_) row.t[0] = 1e9;
  WritePoses(dir_ / "poses_bounds.npy", rows_);
  std::ostringstream log;
  const auto sink = std::make_shared<spdlog::sinks::ostream_sink_mt>(log);
  spdlog::default_logger()->sinks().push_back(sink);
  const Clip clip = LoadClip(dir_.path());  // the clip's geometry is checked on every layout's load
  spdlog::default_logger()->sinks().pop_back();
  EXPECT_EQ(clip.frame_count(), kFrames);
  EXPECT_NE(log.str().find("single-precision coordinates step by about 119"), std::string::npos) << log.str();
}

// A stereo.json without images_right/, and frames that are all black, loaded without a word until
// 2026-12-05.
TEST_F(EndoNerfLoaderTest, AStereoFileWithoutItsEyeAndBlackFramesAreWarnedOf) {
  testing::WriteBytes(dir_ / "stereo.json", R"({"baseline": 5})");
  std::ostringstream log;
  const auto sink = std::make_shared<spdlog::sinks::ostream_sink_mt>(log);
  spdlog::default_logger()->sinks().push_back(sink);
  EXPECT_FALSE(LoadClip(dir_.path()).has_stereo());
  EXPECT_EQ(log.str().find("every frame is black"), std::string::npos) << log.str();
  for (int i = 0; i < kFrames; ++i)
    WriteImage(dir_ / "images" / Name(i), cv::Mat(kH, kW, CV_8UC3, cv::Scalar(1, 1, 1)));
  const Clip black = LoadClip(dir_.path());
  spdlog::default_logger()->sinks().pop_back();
  EXPECT_EQ(int(*std::max_element(black.rgb[0].begin(), black.rgb[0].end())), 1) << "nearly black frames";
  EXPECT_NE(log.str().find("stereo.json without images_right/"), std::string::npos) << log.str();
  EXPECT_NE(log.str().find("every frame is black"), std::string::npos) << log.str();
}

// A job cancelled while its clip loads waited for the whole load (found 2026-12-04): the load asks
// between frames.
TEST_F(EndoNerfLoaderTest, ALoadAskedToStopStopsCancelled) {
  LoadOptions options;
  std::atomic<int> asked = 0;  // asked from the load's threads
  options.should_stop = [&] { return ++asked > 0; };
  const std::string message = ErrorFrom([&] { Load(options); }, ErrorCode::kCancelled);
  EXPECT_NE(message.find("the clip's load was stopped"), std::string::npos) << message;
  EXPECT_GE(asked, 1);
  options.should_stop = [] { return false; };
  EXPECT_EQ(Load(options).frame_count(), kFrames);
}

TEST_F(EndoNerfLoaderTest, ReadsSixteenBitAndNpyDepth) {
  WriteImage(dir_ / "depth" / Name(0), Pattern(kW, kH, CV_16UC1, [](int x, int) { return 1000 + x; }));
  fs::remove(dir_ / "depth" / Name(1));
  const std::vector<float> values(kW * kH, 12.5f);
  WriteNpyFloat32(dir_ / "depth" / "frame-001.npy", values.data(), {kH, kW});
  const Clip clip = Load();
  EXPECT_EQ(clip.depth[0][3], 1003.f);
  EXPECT_EQ(clip.depth[1][3], 12.5f);
}

TEST_F(EndoNerfLoaderTest, ReadsEvalMasksStereoAndForcedStatic) {
  for (int i = 0; i < kFrames; ++i) {
    WriteImage(dir_ / "gt_masks" / Name(i),
               Pattern(kW, kH, CV_8UC1, [](int x, int) { return x == 0 ? 255 : 0; }));
    WriteImage(dir_ / "images_right" / Name(i), Pattern(kW, kH, CV_8UC3, [](int x, int) { return x; }));
  }
  testing::WriteBytes(dir_ / "stereo.json", R"({"baseline": 4.0})");
  LoadOptions options;
  options.force_static = true;
  const Clip clip = Load(options);
  EXPECT_TRUE(clip.is_static);
  ASSERT_EQ(clip.eval_mask.size(), 3u);
  EXPECT_EQ(clip.eval_mask[0][0], 1);
  EXPECT_EQ(clip.eval_mask[0][1], 0);
  ASSERT_TRUE(clip.has_stereo());
  ASSERT_EQ(clip.right_cameras.size(), 3u);
  // The right eye sits 4 units along the left camera's x axis (world +y here).
  EXPECT_TRUE(
      (clip.right_cameras[0].c2w.col(3) - clip.cameras[0].c2w.col(3)).isApprox(Eigen::Vector3d(0, 4, 0)));
  EXPECT_TRUE(clip.right_cameras[0].c2w.leftCols<3>().isApprox(clip.cameras[0].c2w.leftCols<3>()));

  fs::remove(dir_ / "stereo.json");
  const Clip fallback = Load();
  EXPECT_NEAR((fallback.right_cameras[0].c2w.col(3) - fallback.cameras[0].c2w.col(3)).norm(),
              kDefaultStereoBaseline, 1e-12);

  testing::WriteBytes(dir_ / "stereo.json", R"({"baseline": -1})");
  ExpectError("stereo.json", "finite b > 0");
}

TEST_F(EndoNerfLoaderTest, SingleFrameHasTimeZeroAndIsStatic) {
  rows_.resize(1);
  WritePoses(dir_ / "poses_bounds.npy", rows_);
  for (const char* folder : {"images", "depth", "masks"}) {
    for (int i = 1; i < kFrames; ++i) fs::remove(dir_ / folder / Name(i));
  }
  const Clip clip = Load();
  EXPECT_EQ(clip.times, std::vector<float>{0.f});
  EXPECT_TRUE(clip.is_static);
}

TEST(EndoNerfPoseFixtureTest, LoadsRealPoseFileWithDownscaledImages) {
  TempDir dir("endonerf-real");
  fs::copy_file(fs::path(ENDORECON_SHARED_DIR) / "data/endonerf_poses/pulling_soft_tissues/poses_bounds.npy",
                dir / "poses_bounds.npy");
  // 640x512 frames stored at 1/8 scale: 80x64.
  const cv::Mat image = Pattern(80, 64, CV_8UC3, [](int x, int y) { return x + y; });
  for (int i = 0; i < 63; ++i) {
    char name[16];
    std::snprintf(name, sizeof(name), "%03d.png", i);
    WriteImage(dir / "images" / name, image);
  }
  const Clip clip = LoadClip(dir.path());
  ASSERT_EQ(clip.frame_count(), 63);
  EXPECT_EQ(clip.width, 80);
  EXPECT_EQ(clip.height, 64);
  EXPECT_NEAR(clip.cameras[0].fx, 569.46820041 / 8, 1e-9);
  EXPECT_EQ(clip.cameras[0].cx, 40);
  EXPECT_EQ(clip.near, 0);  // EndoNeRF's files have near 0
  EXPECT_EQ(clip.far, 120);
  EXPECT_FLOAT_EQ(clip.times[62], 1.f);
  EXPECT_FLOAT_EQ(clip.times[21], 21.f / 62);
}

TEST_F(EndoNerfLoaderTest, RejectsMissingImagesFolder) {
  fs::remove_all(dir_ / "images");
  ExpectError("images", "folder does not exist");
}

TEST_F(EndoNerfLoaderTest, RejectsMissingPoseFile) {
  fs::remove(dir_ / "poses_bounds.npy");
  ExpectError("poses_bounds.npy", "does not exist");
}

TEST_F(EndoNerfLoaderTest, RejectsUnequalCounts) {
  fs::remove(dir_ / "masks" / Name(1));
  ExpectError("masks", "holds 2 files but poses_bounds.npy has 3 rows");
  // ... and which frame has none (found 2026-12-05: the count alone left the user to search).
  ExpectError("masks", "no file named frame-001.* for images/frame-001.png");
}

TEST_F(EndoNerfLoaderTest, RejectsUnequalSizes) {
  WriteImage(dir_ / "depth" / Name(2), Pattern(kW, kH + 1, CV_8UC1, [](int, int) { return 5; }));
  ExpectError("depth/" + Name(2), "size 8x7 differs from the clip's 8x6");
}

TEST_F(EndoNerfLoaderTest, RejectsImagesNotMatchingThePoseSize) {
  for (PoseRow& row : rows_) row.h = 5;  // 8x5 is not a uniform scaling of 8x6
  WritePoses(dir_ / "poses_bounds.npy", rows_);
  ExpectError(Name(0), "does not match poses_bounds.npy's 8x5");
}

TEST_F(EndoNerfLoaderTest, RejectsTruncatedImage) {
  const fs::path path = dir_ / "images" / Name(1);
  const std::string bytes = testing::ReadBytes(path);
  testing::WriteBytes(path, bytes.substr(0, bytes.size() / 2));
  ExpectError(Name(1), "a truncated PNG: its chunk IDAT at byte");
}

TEST_F(EndoNerfLoaderTest, RejectsNonImageFile) {
  testing::WriteBytes(dir_ / "images" / Name(0), "not a png at all");
  ExpectError(Name(0), "not a PNG, JPEG, BMP or TIFF image");
}

// A frame's name that is no file (a broken link, a link to itself, a folder) is named, where it
// used to be skipped and show only as counts that disagree (or, for the loop, as a bare error).
TEST_F(EndoNerfLoaderTest, RejectsAFrameThatIsNoRegularFile) {
  const fs::path path = dir_ / "images" / Name(1);
  fs::remove(path);
  fs::create_symlink(dir_ / "nowhere.png", path);
  ExpectError(Name(1), "not a regular file");
  fs::remove(path);
  fs::create_symlink(path, path);
  ExpectError(Name(1), "not a regular file");
  fs::remove(path);
  fs::create_directory(path);
  ExpectError(Name(1), "not a regular file");
}

TEST_F(EndoNerfLoaderTest, RejectsNonFinitePose) {
  rows_[1].t[2] = NAN;
  WritePoses(dir_ / "poses_bounds.npy", rows_);
  ExpectError("poses_bounds.npy row 1", "column 13 (t[2]) is NaN; every value must be finite");
  rows_[1].t[2] = 0;
  rows_[2].far = INFINITY;
  WritePoses(dir_ / "poses_bounds.npy", rows_);
  ExpectError("poses_bounds.npy row 2", "column 16 (far) is infinite");
}

TEST_F(EndoNerfLoaderTest, RejectsNonOrthonormalRotation) {
  rows_[2].r[0] = 1.1;
  WritePoses(dir_ / "poses_bounds.npy", rows_);
  ExpectError("poses_bounds.npy row 2", "not orthonormal (max |RᵀR − I| = 0.21)");
}

TEST_F(EndoNerfLoaderTest, RejectsReflection) {
  rows_[0].r[8] = -1;
  WritePoses(dir_ / "poses_bounds.npy", rows_);
  ExpectError("poses_bounds.npy row 0", "determinant -1");
}

TEST_F(EndoNerfLoaderTest, RejectsNonPositiveFocalLength) {
  rows_[1].f = 0;
  WritePoses(dir_ / "poses_bounds.npy", rows_);
  ExpectError("poses_bounds.npy row 1", "focal length must be finite and positive (fx = 0");
}

TEST_F(EndoNerfLoaderTest, RejectsBadImageSizeInPoses) {
  rows_[0].w = 7.5;
  WritePoses(dir_ / "poses_bounds.npy", rows_);
  ExpectError("poses_bounds.npy row 0", "H and W must be positive integers (H = 6, W = 7.5)");
}

TEST_F(EndoNerfLoaderTest, RejectsZeroFrames) {
  WritePoses(dir_ / "poses_bounds.npy", {});
  ExpectError("poses_bounds.npy", "zero frames");
}

TEST_F(EndoNerfLoaderTest, RejectsWrongPoseShape) {
  const std::vector<double> data(3 * 15, 1.0);
  WriteNpyFloat64(dir_ / "poses_bounds.npy", data.data(), {3, 15});
  ExpectError("poses_bounds.npy", "expected an array of shape (N, 17), found (3, 15)");
}

TEST_F(EndoNerfLoaderTest, RejectsNearNotBelowFar) {
  rows_[1].near = 40;
  WritePoses(dir_ / "poses_bounds.npy", rows_);
  ExpectError("poses_bounds.npy row 1", "0 <= near < far (near = 40, far = 29)");
}

// Bounds of 1e-300 and 1e300 overflowed the scene box and training "diverged" at its first step.
TEST_F(EndoNerfLoaderTest, RejectsAFarBoundInImplausibleUnits) {
  rows_[0].far = 1e300;
  WritePoses(dir_ / "poses_bounds.npy", rows_);
  ExpectError("poses_bounds.npy row 0", "the far bound 1e+300 is beyond 1e+12");
}

// A range so thin no sample fits between its bounds (near 29, far 29.000001) rendered black once.
TEST_F(EndoNerfLoaderTest, RejectsADepthRangeTooThinToSample) {
  rows_[1].near = 29;
  rows_[1].far = 29.000001;
  WritePoses(dir_ / "poses_bounds.npy", rows_);
  ExpectError("poses_bounds.npy row 1", "the depth range is too thin to sample");
}

// A translation in other units than the bounds (here 1e9) put every ray outside the scene's box,
// and the run rendered black with exit 0; the clip is refused, naming the spread and the bound.
TEST_F(EndoNerfLoaderTest, RejectsCamerasFartherApartThanTheDepthBoundsAllow) {
  rows_[2].t[0] = 1e9;
  WritePoses(dir_ / "poses_bounds.npy", rows_);
  const std::string message = ErrorFrom([&] { LoadClip(dir_.path(), {}); });
  EXPECT_NE(message.find("the cameras' centres lie 1e+09 apart, more than 10000 times the far bound (30)"),
            std::string::npos)
      << message;
  // A centre past 1e12 from the origin is refused by its row (it was a spread, or "far = inf", with no
  // row; found 2026-12-05).
  rows_[2].t[0] = 1e300;
  WritePoses(dir_ / "poses_bounds.npy", rows_);
  ExpectError("poses_bounds.npy row 2", "the camera's centre lies 1e+300 from the origin");
  rows_[2].t[0] = 5;  // an endoscope's few units of travel: fine
  WritePoses(dir_ / "poses_bounds.npy", rows_);
  EXPECT_EQ(LoadClip(dir_.path(), {}).frame_count(), kFrames);
}

TEST_F(EndoNerfLoaderTest, RejectsFramesOverTheSizeLimit) {
  LoadOptions options;
  options.max_pixels_per_frame = 47;
  const std::string message = ErrorFrom([&] { Load(options); }, ErrorCode::kInvalidArgument);
  EXPECT_NE(message.find("frames of 8x6 (48 pixels) exceed the limit of 47 pixels"), std::string::npos)
      << message;
}

TEST_F(EndoNerfLoaderTest, RejectsMaskWithOtherValues) {
  WriteImage(dir_ / "masks" / Name(1), Pattern(kW, kH, CV_8UC1, [](int x, int) {
               return x < 2 ? 0 : x < 4 ? 17 : 255;
             }));
  ExpectError("masks/" + Name(1), "found values {0, 17, 255}");
}

TEST_F(EndoNerfLoaderTest, RejectsMaskWithThreeChannels) {
  WriteImage(dir_ / "masks" / Name(0), Pattern(kW, kH, CV_8UC3, [](int, int) { return 0; }));
  ExpectError("masks/" + Name(0), "must have one channel, found 3");
}

TEST_F(EndoNerfLoaderTest, RejectsDepthWithNaN) {
  fs::remove(dir_ / "depth" / Name(2));
  std::vector<float> values(kW * kH, 3.f);
  values[kW + 4] = NAN;
  WriteNpyFloat32(dir_ / "depth" / "frame-002.npy", values.data(), {kH, kW});
  ExpectError("frame-002.npy", "depth must be finite and non-negative, found nan at pixel (4, 1)");
}

TEST_F(EndoNerfLoaderTest, RejectsDepthArrayOfWrongShape) {
  fs::remove(dir_ / "depth" / Name(2));
  const std::vector<float> values(kW * kH, 3.f);
  WriteNpyFloat32(dir_ / "depth" / "frame-002.npy", values.data(), {kW, kH});
  ExpectError("frame-002.npy", "shape (8, 6) does not match the clip's 8x6 (expected (6, 8))");
}

}  // namespace
}  // namespace endorecon::scene
