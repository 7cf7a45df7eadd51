// `prepare` end to end on a synthetic recording: the clip it writes loads, says what it did, and
// every input form and option gives what it should.
#include "worker/prepare/prepare_clip.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <fstream>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>

#include "common/npy.h"
#include "tests/unit/clip_fixture.h"
#include "tests/unit/synthetic_recording_fixture.h"
#include "worker/engine/scene/clip_loader.h"
#include "worker/prepare/frame_source.h"

namespace endorecon::testing {
namespace {

namespace fs = std::filesystem;

class PrepareClipTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new TempDir("prepare");
    options_ = RecordingOptions(160, 128, 5);
    scene::WriteSyntheticClip(options_, dir_->path() / "synth");
  }
  static void TearDownTestSuite() {
    delete dir_;
    dir_ = nullptr;
  }
  static fs::path Synth() { return dir_->path() / "synth"; }
  static prepare::PrepareOptions Options(const std::string& out) {
    return RecordingPrepareOptions(Synth(), dir_->path() / out);
  }

  static inline TempDir* dir_ = nullptr;
  static inline scene::SynthOptions options_;
};

std::vector<cv::Mat> ReadFolder(const fs::path& dir) {
  std::vector<cv::Mat> frames;
  auto source = prepare::OpenFrameSource(dir);
  prepare::SourceFrame frame;
  while (source->Next(frame)) frames.push_back(frame.image);
  return frames;
}

TEST_F(PrepareClipTest, WritesALoadableEndoNerfClipThatSaysWhatItDid) {
  const prepare::PrepareSummary summary = prepare::PrepareClip(Options("clip"));
  EXPECT_EQ(summary.layout, "endonerf");
  EXPECT_EQ(summary.frames, 5);
  EXPECT_LT(summary.epipolar_error.median, 0.5);
  const fs::path clip_dir = dir_->path() / "clip";
  for (const char* file :
       {"poses_bounds.npy", "stereo.json", "prepare.json", "preview.png", "images/000004.png",
        "images_right/000004.png", "depth/000004.npy", "masks/000004.png"}) {
    EXPECT_TRUE(fs::exists(clip_dir / file)) << file;
  }
  const nlohmann::json report = ReadJson(clip_dir / "prepare.json");
  const scene::Clip clip = scene::LoadClip(clip_dir);
  ASSERT_EQ(clip.frame_count(), 5);
  EXPECT_EQ(clip.width, report["rectification"]["size"][0].get<int>());
  EXPECT_EQ(clip.cameras[0].cx, clip.width / 2.0);
  EXPECT_NEAR(clip.cameras[0].fx, report["rectification"]["focal_px"].get<double>(), 1e-9);
  EXPECT_TRUE(clip.cameras[0].c2w.isApprox(Eigen::Matrix<double, 3, 4>::Identity()));
  ASSERT_TRUE(clip.has_stereo());
  EXPECT_NEAR(clip.right_cameras[0].c2w(0, 3), 5.0, 0.01);
  ASSERT_TRUE(clip.has_masks());
  ASSERT_TRUE(clip.has_depth());
  EXPECT_GT(clip.near, 0);
  for (int f = 0; f < clip.frame_count(); ++f) {
    for (float z : clip.depth[f]) {
      if (z > 0) {
        ASSERT_TRUE(z >= clip.near && z <= clip.far) << z;
      }
    }
  }
  EXPECT_EQ(report["frames"].size(), 5u);
  EXPECT_EQ(report["recording"]["frames"], 5);
  EXPECT_GT(report["frames"][2]["depth_coverage"].get<double>(), 0.8);
  EXPECT_EQ(report["calibration"]["kind"], "opencv");
  const cv::Mat preview = cv::imread((clip_dir / "preview.png").string());
  EXPECT_EQ(preview.cols, 3 * clip.width) << "frame, depth and mask side by side";
}

TEST_F(PrepareClipTest, VideosAndCombinedFramesGiveTheSameClip) {
  // Side by side and top-bottom as image folders (lossless): the same pixels as two folders.
  const std::vector<cv::Mat> left = ReadFolder(Synth() / "recording/left"),
                             right = ReadFolder(Synth() / "recording/right");
  cv::VideoWriter left_video((dir_->path() / "left.avi").string(), cv::CAP_OPENCV_MJPEG,
                             cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 25, left[0].size());
  cv::VideoWriter right_video((dir_->path() / "right.avi").string(), cv::CAP_OPENCV_MJPEG,
                              cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 25, left[0].size());
  for (std::size_t i = 0; i < left.size(); ++i) {
    cv::Mat both;
    cv::hconcat(left[i], right[i], both);
    WriteImage(dir_->path() / "sbs" / (std::to_string(i) + ".png"), both);
    cv::vconcat(left[i], right[i], both);
    WriteImage(dir_->path() / "tb" / (std::to_string(i) + ".png"), both);
    left_video.write(left[i]);
    right_video.write(right[i]);
  }
  left_video.release();
  right_video.release();

  prepare::PrepareClip(Options("two"));
  prepare::PrepareOptions sbs = Options("sbs-clip");
  sbs.recording = {prepare::StereoLayout::kSideBySide, {}, {}, dir_->path() / "sbs"};
  prepare::PrepareClip(sbs);
  prepare::PrepareOptions tb = Options("tb-clip");
  tb.recording = {prepare::StereoLayout::kTopBottom, {}, {}, dir_->path() / "tb"};
  prepare::PrepareClip(tb);
  for (const char* file : {"images/000003.png", "depth/000003.npy", "masks/000003.png"}) {
    EXPECT_EQ(ReadBytes(dir_->path() / "two" / file), ReadBytes(dir_->path() / "sbs-clip" / file)) << file;
    EXPECT_EQ(ReadBytes(dir_->path() / "two" / file), ReadBytes(dir_->path() / "tb-clip" / file)) << file;
  }

  prepare::PrepareOptions video = Options("video-clip");
  video.recording = {
      prepare::StereoLayout::kTwoSources, dir_->path() / "left.avi", dir_->path() / "right.avi", {}};
  const prepare::PrepareSummary summary = prepare::PrepareClip(video);
  EXPECT_EQ(summary.frames, 5);
  EXPECT_GT(summary.depth_coverage, 0.8) << "Motion-JPEG's losses leave the depth nearly whole";
  const nlohmann::json report = ReadJson(dir_->path() / "video-clip/prepare.json");
  EXPECT_NEAR(report["frames"][4]["time_s"].get<double>(), 4 / 25.0, 1e-6);
}

TEST_F(PrepareClipTest, FramesSizeExcludedRegionsAndBlackMasks) {
  // The masks inverted (tool black) and said so give the same masks.
  for (const fs::path& file : fs::directory_iterator(Synth() / "recording/masks")) {
    WriteImage(dir_->path() / "black-masks" / file.filename(),
               255 - cv::imread(file.string(), cv::IMREAD_GRAYSCALE));
  }
  prepare::PrepareOptions options = Options("options-clip");
  options.masks = dir_->path() / "black-masks";
  options.masks_tool_black = true;
  options.frames = ParseFrameRange("1:5:2");
  options.size = ParseFrameSize("120x96");
  options.exclude = {ParsePixelRect("0,0,40,20")};
  const prepare::PrepareSummary summary = prepare::PrepareClip(options);
  EXPECT_EQ(summary.frames, 2);
  const nlohmann::json report = ReadJson(dir_->path() / "options-clip/prepare.json");
  EXPECT_EQ(report["frames"][0]["recording_frame"], 1);
  EXPECT_EQ(report["frames"][1]["recording_frame"], 3);
  const scene::Clip clip = scene::LoadClip(dir_->path() / "options-clip");
  EXPECT_EQ(clip.width, 120);
  EXPECT_EQ(clip.height, 96);
  // The excluded corner is excluded and has no depth; the tool is masked as in white masks.
  EXPECT_EQ(clip.tool_mask[0][0], 1);
  EXPECT_EQ(clip.depth[0][0], 0.f);
  std::size_t tool = 0;
  for (std::size_t p = 0; p < clip.tool_mask[1].size(); ++p) tool += clip.tool_mask[1][p];
  EXPECT_GT(tool, clip.tool_mask[1].size() / 20);
  EXPECT_LT(tool, clip.tool_mask[1].size() / 2);
}

TEST_F(PrepareClipTest, RosCalibrationPairGivesTheSameClip) {
  const prepare::StereoCalibration rig =
      prepare::LoadStereoCalibration({Synth() / "recording/calibration.yaml"});
  cv::Mat r1, r2, p1, p2, q;
  cv::stereoRectify(rig.k1, rig.d1, rig.k2, rig.d2, rig.image_size, rig.r, rig.t, r1, r2, p1, p2, q,
                    cv::CALIB_ZERO_DISPARITY, 0);
  const auto write = [&](const fs::path& path, const cv::Matx33d& k, const cv::Mat& d, const cv::Mat& r,
                         const cv::Mat& p) {
    std::ofstream out(path);
    const auto list = [](const cv::Mat& m) {
      std::string text = "[";
      for (int i = 0; i < m.rows * m.cols; ++i)
        text += (i ? ", " : "") + cv::format("%.17g", m.at<double>(i / m.cols, i % m.cols));
      return text + "]";
    };
    out << "image_width: " << rig.image_size.width << "\nimage_height: " << rig.image_size.height
        << "\ncamera_matrix:\n  rows: 3\n  cols: 3\n  data: " << list(cv::Mat(k))
        << "\ndistortion_model: plumb_bob\ndistortion_coefficients:\n  rows: 1\n  cols: 5\n  data: "
        << list(d) << "\nrectification_matrix:\n  rows: 3\n  cols: 3\n  data: " << list(r)
        << "\nprojection_matrix:\n  rows: 3\n  cols: 4\n  data: " << list(p) << "\n";
  };
  write(dir_->path() / "left.yaml", rig.k1, rig.d1, r1, p1);
  write(dir_->path() / "right.yaml", rig.k2, rig.d2, r2, p2);
  prepare::PrepareOptions ros = Options("ros-clip");
  ros.calibration = {dir_->path() / "left.yaml", dir_->path() / "right.yaml"};
  prepare::PrepareClip(ros);
  prepare::PrepareClip(Options("opencv-clip"));
  const nlohmann::json a = ReadJson(dir_->path() / "ros-clip/prepare.json"),
                       b = ReadJson(dir_->path() / "opencv-clip/prepare.json");
  EXPECT_EQ(a["calibration"]["kind"], "ros");
  EXPECT_EQ(a["rectification"]["size"], b["rectification"]["size"]);
  EXPECT_NEAR(a["rectification"]["focal_px"].get<double>(), b["rectification"]["focal_px"].get<double>(),
              1e-6);
  const cv::Mat ia = cv::imread((dir_->path() / "ros-clip/images/000002.png").string());
  const cv::Mat ib = cv::imread((dir_->path() / "opencv-clip/images/000002.png").string());
  EXPECT_LE(cv::norm(ia, ib, cv::NORM_INF), 1);
}

TEST_F(PrepareClipTest, PoseFilesMoveTheCamera) {
  // The synthetic recording's poses.json is the identity for a fixed endoscope: the EndoNeRF layout.
  prepare::PrepareOptions fixed = Options("fixed-poses");
  fixed.poses = Synth() / "recording/poses.json";
  EXPECT_EQ(prepare::PrepareClip(fixed).layout, "endonerf");

  // Moving poses (CSV, OpenCV axes): transforms.json with the rectified camera's poses.
  {
    std::ofstream csv(dir_->path() / "poses.csv");
    csv << "# camera-to-world of the left eye, row-major 3x4\n";
    for (int i = 0; i < 5; ++i) csv << "1,0,0," << i << ",0,1,0,0,0,0,1," << -0.5 * i << "\n";
  }
  prepare::PrepareOptions moving = Options("moving-poses");
  moving.poses = dir_->path() / "poses.csv";
  EXPECT_EQ(prepare::PrepareClip(moving).layout, "transforms");
  EXPECT_TRUE(fs::exists(dir_->path() / "moving-poses/transforms.json"));
  const scene::Clip clip = scene::LoadClip(dir_->path() / "moving-poses");
  ASSERT_EQ(clip.frame_count(), 5);
  // Centres are the file's (world coordinates); the rotation is the rectifying one's inverse.
  EXPECT_NEAR(clip.cameras[3].c2w(0, 3), 3, 1e-9);
  EXPECT_NEAR(clip.cameras[3].c2w(2, 3), -1.5, 1e-9);
  EXPECT_FALSE(clip.cameras[0].c2w.leftCols<3>().isApprox(Eigen::Matrix3d::Identity(), 1e-6));
  EXPECT_TRUE(clip.has_masks());
  EXPECT_FLOAT_EQ(clip.times[4], 1.f);
}

TEST_F(PrepareClipTest, ReplacesAnEarlierPreparedClipButNothingElse) {
  prepare::PrepareOptions options = Options("again");
  // A run killed before it finished left its staging folder; the next run of the same output
  // removes it (its process, pid 999999999 here, is gone), and leaves a live process's alone.
  const fs::path abandoned = dir_->path() / ".again.preparing-999999999";
  const fs::path live = dir_->path() / (".again.preparing-" + std::to_string(::getppid()));
  fs::create_directories(abandoned / "images");
  fs::create_directories(live);
  prepare::PrepareClip(options);
  EXPECT_FALSE(fs::exists(abandoned));
  EXPECT_TRUE(fs::exists(live));
  options.frames = ParseFrameRange("0:2");
  EXPECT_EQ(prepare::PrepareClip(options).frames, 2);
  EXPECT_FALSE(fs::exists(dir_->path() / "again/images/000003.png"));
  fs::create_directories(dir_->path() / "foreign");
  WriteBytes(dir_->path() / "foreign/notes.txt", "keep me");
  options.out = dir_->path() / "foreign";
  const std::string message = ErrorFrom([&] { prepare::PrepareClip(options); });
  EXPECT_NE(message.find("exists and is not empty"), std::string::npos) << message;
  EXPECT_TRUE(fs::exists(dir_->path() / "foreign/notes.txt"));
}

}  // namespace
}  // namespace endorecon::testing
