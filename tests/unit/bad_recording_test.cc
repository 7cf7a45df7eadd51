// Every bad input of issue 16 (section 4): a clear error naming the file and the frame, and no
// clip, half-written or otherwise, left behind.
#include <gtest/gtest.h>

#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>

#include "tests/unit/clip_fixture.h"
#include "tests/unit/temp_dir.h"
#include "worker/prepare/prepare_clip.h"
#include "worker/prepare/stereo_calibration.h"

namespace endorecon::testing {
namespace {

namespace fs = std::filesystem;

// Textured frames and copies shifted by 6 pixels: a rectified pair.
cv::Mat Texture(int i, cv::Size size) {
  cv::Mat image(size, CV_8UC3);
  cv::RNG random(static_cast<std::uint64_t>(i) + 7);
  random.fill(image, cv::RNG::UNIFORM, 30, 200);
  return image;
}

void WritePair(const fs::path& dir, int frames, cv::Size size = {64, 48}) {
  for (int i = 0; i < frames; ++i) {
    const cv::Mat left = Texture(i, size);
    cv::Mat right(size, CV_8UC3, cv::Scalar::all(0));
    left(cv::Rect(6, 0, size.width - 6, size.height))
        .copyTo(right(cv::Rect(0, 0, size.width - 6, size.height)));
    WriteImage(dir / "left" / (std::to_string(100 + i) + ".png"), left);
    WriteImage(dir / "right" / (std::to_string(100 + i) + ".png"), right);
  }
}

class BadRecordingTest : public ::testing::Test {
 protected:
  void SetUp() override { WritePair(dir_.path(), 6); }

  prepare::PrepareOptions Options() const {
    prepare::PrepareOptions options;
    options.recording = {prepare::StereoLayout::kTwoSources, dir_ / "left", dir_ / "right", {}};
    options.rectified = true;
    options.focal = 60;
    options.baseline = 4;
    options.out = dir_ / "clip";
    return options;
  }

  // The error PrepareClip throws; checks that nothing was left in the output's folder.
  std::string Refused(const prepare::PrepareOptions& options, ErrorCode code = ErrorCode::kInvalidArgument) {
    const std::string message = ErrorFrom([&] { prepare::PrepareClip(options); }, code);
    EXPECT_FALSE(fs::exists(options.out)) << "a clip was left behind";
    for (const auto& entry : fs::directory_iterator(options.out.parent_path())) {
      EXPECT_EQ(entry.path().filename().string().find(".preparing"), std::string::npos) << entry.path();
    }
    return message;
  }

  TempDir dir_{"bad-recording"};
};

TEST_F(BadRecordingTest, GoodRecordingPasses) { EXPECT_EQ(prepare::PrepareClip(Options()).frames, 6); }

TEST_F(BadRecordingTest, EyesOfDifferentLengths) {
  fs::remove(dir_ / "right/105.png");
  // Two folders' counts are exact: refused before any frame is prepared.
  const std::string message = Refused(Options());
  EXPECT_NE(message.find("right: 5 frames while "), std::string::npos) << message;
  EXPECT_NE(message.find("left has 6 (both eyes' recordings must have the same length; if one eye's began "
                         "earlier, pass --skip-left or --skip-right"),
            std::string::npos)
      << message;
}

// One eye given twice prepared a clip of 29% depth coverage without a word (found 2026-12-05).
TEST_F(BadRecordingTest, OneEyeGivenTwice) {
  auto options = Options();
  options.recording.right = dir_ / "left" / ".." / "left";
  const std::string message = Refused(options);
  EXPECT_NE(message.find("the right eye is the left eye's recording"), std::string::npos) << message;
}

TEST_F(BadRecordingTest, EyesOfDifferentSizes) {
  fs::remove_all(dir_ / "right");
  for (int i = 0; i < 6; ++i) WriteImage(dir_ / "right" / (std::to_string(i) + ".png"), Texture(i, {64, 40}));
  const std::string message = Refused(Options());
  EXPECT_NE(message.find("right: frames of 64x40 differ from"), std::string::npos) << message;
}

TEST_F(BadRecordingTest, FrameOfAnotherSizeMidway) {
  WriteImage(dir_ / "left/103.png", Texture(3, {32, 48}));
  const std::string message = Refused(Options());
  EXPECT_NE(message.find("103.png: size 32x48 differs from the recording's 64x48"), std::string::npos)
      << message;
}

TEST_F(BadRecordingTest, CalibrationForAnotherImageSize) {
  prepare::WriteStereoCalibration(dir_ / "calibration.yaml", prepare::RectifiedCalibration({128, 96}, 60, 4));
  prepare::PrepareOptions options = Options();
  options.rectified = false;
  options.calibration = {dir_ / "calibration.yaml"};
  const std::string message = Refused(options);
  EXPECT_NE(message.find(
                "calibration.yaml: the calibration is for 128x96 images but the recording's eyes are 64x48"),
            std::string::npos)
      << message;
}

// A calibration file may leave the image size out (docs/formats.md): the recording's is taken. It
// failed with OpenCV's "Matrix operand is an empty matrix" (found 2026-12-06).
TEST_F(BadRecordingTest, CalibrationWithoutItsImageSizeIsTheRecordings) {
  const prepare::StereoCalibration rig = prepare::RectifiedCalibration({64, 48}, 60, 4);
  {
    cv::FileStorage file((dir_ / "calibration.yaml").string(), cv::FileStorage::WRITE);
    file << "K1" << cv::Mat(rig.k1) << "D1" << rig.d1 << "K2" << cv::Mat(rig.k2) << "D2" << rig.d2 << "R"
         << cv::Mat(rig.r) << "T" << cv::Mat(rig.t);
  }
  prepare::PrepareOptions options = Options();
  options.rectified = false;
  options.calibration = {dir_ / "calibration.yaml"};
  EXPECT_EQ(prepare::PrepareClip(options).frames, 6);
}

// Swapped eyes prepared a clip with a third of its depth, too far, without a word (found 2026-12-06).
TEST_F(BadRecordingTest, EyesTheOtherWayRound) {
  prepare::PrepareOptions options = Options();
  std::swap(options.recording.left, options.recording.right);
  const std::string message = Refused(options);
  EXPECT_NE(message.find("the points of the left eye lie further left in the right eye (a median disparity "
                         "of -6"),
            std::string::npos)
      << message;
  EXPECT_NE(message.find("the eyes are given the other way round (swap --left and --right, or the halves of "
                         "the frame; if the other way gives this too, the calibration is not this rig's)"),
            std::string::npos)
      << message;
}

// One picture given as both eyes (a mono recording as stereo) read as swapped eyes, whose swap said
// the same, or prepared 0% depth (found 2026-12-06).
TEST_F(BadRecordingTest, OnePictureGivenAsBothEyes) {
  fs::create_directories(dir_ / "copy");
  for (const auto& entry : fs::directory_iterator(dir_ / "left"))
    fs::copy_file(entry.path(), dir_ / "copy" / entry.path().filename());
  prepare::PrepareOptions options = Options();
  options.recording.right = dir_ / "copy";
  const std::string message = Refused(options);
  EXPECT_NE(message.find("the two eyes show the same picture (under a grey level apart on average in each of "
                         "the 6 pairs surveyed): a mono recording given as stereo, or a scene too far"),
            std::string::npos)
      << message;
}

// Two views of a dark scene differ by little too, but by as much as the scene varies: not one picture.
TEST_F(BadRecordingTest, ADarkPairIsNotOnePicture) {
  for (const char* eye : {"left", "right"}) {
    for (const auto& entry : fs::directory_iterator(dir_ / eye)) {
      cv::Mat image = cv::imread(entry.path().string());
      image.convertTo(image, CV_8U, 0.012);  // 30..200 becomes 0..2 grey levels: under one apart
      WriteImage(entry.path(), image);
    }
  }
  EXPECT_EQ(prepare::PrepareClip(Options()).frames, 6);
}

// The eyes' frames are paired by their order: recordings of other rates or lengths are refused before
// any frame is prepared (a 25 and a 30 fps eye prepared a clip without a word; found 2026-12-06).
TEST_F(BadRecordingTest, EyesOfDifferentFrameRatesOrLengths) {
  // An eye's video: the left eye's texture, or the right eye's, shifted by 6 pixels.
  const auto video = [&](const std::string& name, double fps, int frames, bool left_eye = false) {
    cv::VideoWriter writer((dir_ / name).string(), cv::CAP_OPENCV_MJPEG,
                           cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), fps, cv::Size(64, 48));
    for (int i = 0; i < frames; ++i) {
      const cv::Mat left = Texture(i, {64, 48});
      cv::Mat right(left.size(), CV_8UC3, cv::Scalar::all(0));
      left(cv::Rect(6, 0, 58, 48)).copyTo(right(cv::Rect(0, 0, 58, 48)));
      writer.write(left_eye ? left : right);
    }
    return dir_ / name;
  };
  prepare::PrepareOptions options = Options();
  options.recording.left = video("left.avi", 25, 12, true);
  options.recording.right = video("right30.avi", 30, 12);
  std::string message = Refused(options);
  EXPECT_NE(message.find("right30.avi: 30 frames per second while "), std::string::npos) << message;
  EXPECT_NE(message.find("left.avi has 25: the eyes' frames are paired by their order"), std::string::npos)
      << message;
  // Two videos' lengths are compared as they end (a header's count may be an estimate): one shorter
  // by more than two frames is refused, one longer by a trailing frame or two is paired up to the
  // shorter.
  options.recording.right = video("right_short.avi", 25, 8);
  message = Refused(options);
  EXPECT_NE(message.find("right_short.avi frame 8: it ends after 8 frames while "), std::string::npos)
      << message;
  EXPECT_NE(message.find("left.avi goes on (both eyes' recordings must have the same length)"),
            std::string::npos)
      << message;
  options.recording.right = video("right_longer.avi", 25, 13);
  EXPECT_EQ(prepare::PrepareClip(options).frames, 12);
  // A folder has no rate (its times are its order at 25 fps): beside a 30 fps video it is paired by
  // order, its times not compared.
  WritePair(dir_ / "long", 20);  // 20 frames: 0.76 s at 25 fps against 0.63 s at 30
  {
    cv::VideoWriter writer((dir_ / "long" / "right30.avi").string(), cv::CAP_OPENCV_MJPEG,
                           cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 30, cv::Size(64, 48));
    for (int i = 0; i < 20; ++i)
      writer.write(cv::imread((dir_ / "long" / "right" / (std::to_string(100 + i) + ".png")).string()));
  }
  options = Options();
  options.recording.left = dir_ / "long" / "left";
  options.recording.right = dir_ / "long" / "right30.avi";
  EXPECT_EQ(prepare::PrepareClip(options).frames, 20);
}

TEST_F(BadRecordingTest, UnreadableAndTruncatedVideos) {
  WriteBytes(dir_ / "noise.mp4", std::string(4096, 'z'));
  prepare::PrepareOptions options = Options();
  options.recording.left = dir_ / "noise.mp4";
  std::string message = Refused(options);
  EXPECT_NE(message.find("noise.mp4: cannot open it as a video"), std::string::npos) << message;

  cv::VideoWriter writer((dir_ / "full.avi").string(), cv::CAP_OPENCV_MJPEG,
                         cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 25, cv::Size(64, 48));
  for (int i = 0; i < 40; ++i) writer.write(Texture(i, {64, 48}));
  writer.release();
  const std::string bytes = ReadBytes(dir_ / "full.avi");
  WriteBytes(dir_ / "cut.avi", bytes.substr(0, bytes.size() / 2));
  options.recording = {prepare::StereoLayout::kSideBySide, {}, {}, dir_ / "cut.avi"};
  message = Refused(options);
  EXPECT_NE(message.find("cut.avi frame "), std::string::npos) << message;
  EXPECT_NE(message.find("truncated or damaged"), std::string::npos) << message;
}

TEST_F(BadRecordingTest, SideBySideFrameOfOddWidth) {
  for (int i = 0; i < 3; ++i) WriteImage(dir_ / "sbs" / (std::to_string(i) + ".png"), Texture(i, {65, 48}));
  prepare::PrepareOptions options = Options();
  options.recording = {prepare::StereoLayout::kSideBySide, {}, {}, dir_ / "sbs"};
  const std::string message = Refused(options);
  EXPECT_NE(message.find("sbs frame 0: a side-by-side frame must have an even width, found 65x48"),
            std::string::npos)
      << message;
  options.recording.layout = prepare::StereoLayout::kTopBottom;
  for (int i = 0; i < 3; ++i) WriteImage(dir_ / "sbs" / (std::to_string(i) + ".png"), Texture(i, {64, 47}));
  EXPECT_NE(Refused(options).find("must have an even height, found 64x47"), std::string::npos);
}

TEST_F(BadRecordingTest, MasksThatDoNotMatch) {
  prepare::PrepareOptions options = Options();
  options.masks = dir_ / "masks";
  for (int i = 0; i < 6; ++i)
    WriteImage(dir_ / "masks" / (std::to_string(i) + ".png"), cv::Mat(40, 64, CV_8U, cv::Scalar(0)));
  std::string message = Refused(options);
  EXPECT_NE(message.find("masks frame 0: masks of 64x40 do not match the left eye's 64x48 frames"),
            std::string::npos)
      << message;

  fs::remove_all(dir_ / "masks");
  for (int i = 0; i < 5; ++i)
    WriteImage(dir_ / "masks" / (std::to_string(i) + ".png"), cv::Mat(48, 64, CV_8U, cv::Scalar(0)));
  message = Refused(options);
  // Two folders: the counts are compared before any frame is prepared (found 2026-12-07).
  EXPECT_NE(message.find("masks: holds 5 mask frames, fewer than the left eye's 6 (one mask per frame)"),
            std::string::npos)
      << message;

  for (int i = 5; i < 7; ++i)
    WriteImage(dir_ / "masks" / (std::to_string(i) + ".png"), cv::Mat(48, 64, CV_8U, cv::Scalar(0)));
  message = Refused(options);
  EXPECT_NE(message.find("masks: holds more mask frames than the left eye's 6"), std::string::npos)
      << message;
}

// --skip-left drops the left eye's first frames, and their masks and poses with them; the counts are
// still checked against the left eye's file, and said as the files count them (a skip let any number
// of masks through, and poses were not skipped; found 2026-12-07).
TEST_F(BadRecordingTest, ASkipDropsTheLeftEyesMasksAndPosesAndTheirCountsAreStillChecked) {
  fs::remove(dir_ / "left/100.png");  // the left eye's file began a frame after the right's
  WriteImage(dir_ / "left/106.png", Texture(6, {64, 48}));
  WriteImage(dir_ / "left/107.png", Texture(7, {64, 48}));
  // left: 7 frames (101-107), right: 6 (100-105); --skip-right 1 pairs 101-105 with 101-105.
  prepare::PrepareOptions options = Options();
  options.recording.skip_right = 1;
  options.masks = dir_ / "masks";
  const auto masks = [&](int count) {
    fs::remove_all(dir_ / "masks");
    for (int i = 0; i < count; ++i)
      WriteImage(dir_ / "masks" / (std::to_string(i) + ".png"), cv::Mat(48, 64, CV_8U, cv::Scalar(0)));
  };
  masks(7);
  EXPECT_EQ(prepare::PrepareClip(options).frames, 5);  // the right eye's recording ended first
  fs::remove_all(options.out);
  // A left eye's file that began 2 frames before the right's: its frames 2-7 pair with the right's 0-5.
  for (int i = 0; i < 8; ++i)
    WriteImage(dir_ / "left2" / (std::to_string(100 + i) + ".png"), Texture(i - 2, {64, 48}));
  options.recording = {prepare::StereoLayout::kTwoSources, dir_ / "left2", dir_ / "right", {}, 2, 0};
  masks(9);
  std::string message = Refused(options);
  EXPECT_NE(
      message.find("masks: holds more mask frames than the left eye's 8 (6 after the 2 of --skip-left)"),
      std::string::npos)
      << message;
  masks(5);
  message = Refused(options);
  EXPECT_NE(
      message.find("masks: holds 5 mask frames, fewer than the left eye's 8 (6 after the 2 of --skip-left)"),
      std::string::npos)
      << message;
  masks(8);
  EXPECT_EQ(prepare::PrepareClip(options).frames, 6);
  const std::string report = ReadBytes(options.out / "prepare.json");
  EXPECT_NE(report.find("\"skip_left\": 2"), std::string::npos) << report;
  fs::remove_all(options.out);
  options.masks.clear();
  // One pose per frame of the left eye's file: the skipped frames' are skipped.
  options.poses = dir_ / "poses.csv";
  const auto poses = [&](int count) {
    std::ofstream csv(options.poses);
    for (int i = 0; i < count; ++i) csv << "1,0,0,0, 0,1,0,0, 0,0,1," << i << "\n";
  };
  poses(8);
  EXPECT_EQ(prepare::PrepareClip(options).frames, 6);
  fs::remove_all(options.out);
  poses(4);
  message = Refused(options);
  EXPECT_NE(message.find(
                "poses.csv: holds 4 poses but the recording has 8 frames (2 of them dropped by --skip-left)"),
            std::string::npos)
      << message;
  poses(9);
  message = Refused(options);
  EXPECT_NE(message.find("poses.csv: holds 9 poses but the recording has 8 frames (2 of them dropped by "
                         "--skip-left)"),
            std::string::npos)
      << message;
  // A skip of every frame of a folder is refused at once, naming the eye and its flag.
  options.poses.clear();
  options.recording.skip_left = 8;
  message = Refused(options);
  EXPECT_NE(message.find("left2: it holds 8 frame(s): none is left after the 8 skipped (--skip-left 8)"),
            std::string::npos)
      << message;
}

TEST_F(BadRecordingTest, PoseFilesOfTheWrongCountOrNotRigid) {
  prepare::PrepareOptions options = Options();
  options.poses = dir_ / "poses.csv";
  {
    std::ofstream csv(options.poses);
    for (int i = 0; i < 5; ++i) csv << "1,0,0,0, 0,1,0,0, 0,0,1," << i << "\n";
  }
  std::string message = Refused(options);
  EXPECT_NE(message.find("poses.csv: holds 5 poses but the recording has 6 frames (one pose per frame)"),
            std::string::npos)
      << message;
  {
    std::ofstream csv(options.poses);
    for (int i = 0; i < 7; ++i) csv << "1,0,0,0, 0,1,0,0, 0,0,1," << i << "\n";
  }
  message = Refused(options);
  EXPECT_NE(message.find("poses.csv: holds 7 poses but the recording has 6 frames"), std::string::npos)
      << message;

  options.poses = dir_ / "poses.json";
  WriteBytes(
      options.poses,
      R"({"poses": [[[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]], [[2,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]]})");
  message = Refused(options);
  EXPECT_NE(message.find("poses.json frame 1: the rotation is not orthonormal"), std::string::npos)
      << message;
  WriteBytes(options.poses, R"({"poses": [[[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0.5,0,1]]]})");
  message = Refused(options);
  EXPECT_NE(message.find("poses.json frame 0: the last row must be [0, 0, 0, 1]"), std::string::npos)
      << message;
}

TEST_F(BadRecordingTest, OptionsThatContradictEachOther) {
  prepare::PrepareOptions options = Options();
  options.calibration = {dir_ / "calibration.yaml"};
  EXPECT_NE(Refused(options).find("give either --calibration"), std::string::npos);
  options = Options();
  options.poses = dir_ / "poses.csv";
  options.estimate_poses = true;
  EXPECT_NE(Refused(options).find("not both"), std::string::npos);
  options = Options();
  options.exclude = {ParsePixelRect("60,40,10,10")};
  EXPECT_NE(Refused(options).find("--exclude 60,40,10,10 reaches outside the recording's 64x48 frames"),
            std::string::npos);
  options = Options();
  options.frames = ParseFrameRange("10:");
  EXPECT_NE(Refused(options).find("no frame selected by --frames 10::1 (the recording has 6)"),
            std::string::npos);
  options = Options();
  options.recording.right = dir_ / "absent";
  Refused(options, ErrorCode::kNotFound);
}

}  // namespace
}  // namespace endorecon::testing
