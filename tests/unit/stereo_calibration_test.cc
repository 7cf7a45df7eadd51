// Calibration files: OpenCV's stereo file, a pair of ROS camera_info YAMLs describing the same rig,
// and the faults each can have.
#include "worker/prepare/stereo_calibration.h"

#include <gtest/gtest.h>

#include <fstream>
#include <opencv2/calib3d.hpp>

#include "tests/unit/clip_fixture.h"
#include "tests/unit/temp_dir.h"

namespace endorecon::testing {
namespace {

namespace fs = std::filesystem;

prepare::StereoCalibration Rig() {
  prepare::StereoCalibration c;
  c.image_size = {640, 512};
  c.k1 = {600, 0, 322, 0, 601, 250, 0, 0, 1};
  c.k2 = {604, 0, 318, 0, 605, 259, 0, 0, 1};
  c.d1 = (cv::Mat_<double>(1, 5) << -0.2, 0.08, 0.001, -0.001, 0);
  c.d2 = (cv::Mat_<double>(1, 5) << -0.19, 0.07, -0.001, 0.001, 0);
  cv::Rodrigues(cv::Vec3d(0.004, -0.009, 0.006), c.r);
  c.t = -(c.r * cv::Vec3d(5, 0.06, -0.04));
  return c;
}

std::string RosMatrix(const char* name, const cv::Mat& m) {
  std::string text = std::string(name) + ":\n  rows: " + std::to_string(m.rows) +
                     "\n  cols: " + std::to_string(m.cols) + "\n  data: [";
  for (int i = 0; i < m.rows * m.cols; ++i)
    text += (i ? ", " : "") + cv::format("%.17g", m.at<double>(i / m.cols, i % m.cols));
  return text + "]\n";
}

// The rig as ROS's camera_calibration writes it: each eye's K, D, rectifying rotation and
// rectified projection.
void WriteRosPair(const prepare::StereoCalibration& c, const fs::path& left, const fs::path& right) {
  cv::Mat r1, r2, p1, p2, q;
  cv::stereoRectify(c.k1, c.d1, c.k2, c.d2, c.image_size, c.r, c.t, r1, r2, p1, p2, q,
                    cv::CALIB_ZERO_DISPARITY, 0);
  const auto write = [&](const fs::path& path, const cv::Matx33d& k, const cv::Mat& d, const cv::Mat& r,
                         const cv::Mat& p) {
    std::ofstream out(path);
    out << "image_width: " << c.image_size.width << "\nimage_height: " << c.image_size.height
        << "\ncamera_name: endoscope\n"
        << RosMatrix("camera_matrix", cv::Mat(k)) << "distortion_model: plumb_bob\n"
        << RosMatrix("distortion_coefficients", d) << RosMatrix("rectification_matrix", r)
        << RosMatrix("projection_matrix", p);
  };
  write(left, c.k1, c.d1, r1, p1);
  write(right, c.k2, c.d2, r2, p2);
}

TEST(StereoCalibrationTest, OpenCvFileRoundTrips) {
  TempDir dir("calibration");
  const prepare::StereoCalibration rig = Rig();
  prepare::WriteStereoCalibration(dir / "rig.yaml", rig, {{"rms_reprojection_error_px", 0.2}});
  prepare::WriteStereoCalibration(dir / "rig.xml", rig);
  for (const char* name : {"rig.yaml", "rig.xml"}) {
    const prepare::StereoCalibration loaded = prepare::LoadStereoCalibration({dir / name});
    EXPECT_EQ(loaded.kind, "opencv");
    EXPECT_EQ(loaded.image_size, rig.image_size);
    EXPECT_LT(cv::norm(loaded.k1 - rig.k1), 1e-9);
    EXPECT_LT(cv::norm(loaded.d2, rig.d2), 1e-12);
    EXPECT_LT(cv::norm(loaded.r - rig.r), 1e-12);
    EXPECT_NEAR(loaded.baseline(), rig.baseline(), 1e-12);
  }
}

TEST(StereoCalibrationTest, RosPairDescribesTheSameRig) {
  TempDir dir("calibration");
  const prepare::StereoCalibration rig = Rig();
  WriteRosPair(rig, dir / "left.yaml", dir / "right.yaml");
  const prepare::StereoCalibration loaded =
      prepare::LoadStereoCalibration({dir / "left.yaml", dir / "right.yaml"});
  EXPECT_EQ(loaded.kind, "ros");
  EXPECT_EQ(loaded.image_size, rig.image_size);
  EXPECT_LT(cv::norm(loaded.k2 - rig.k2), 1e-9);
  EXPECT_LT(cv::norm(loaded.r - rig.r), 1e-9);
  EXPECT_LT(cv::norm(loaded.t - rig.t), 1e-9) << loaded.t << " vs " << rig.t;
}

TEST(StereoCalibrationTest, FaultsNameTheFileAndField) {
  TempDir dir("calibration");
  prepare::StereoCalibration rig = Rig();
  {
    cv::FileStorage file((dir / "no_t.yaml").string(), cv::FileStorage::WRITE);
    file << "K1" << cv::Mat(rig.k1) << "D1" << rig.d1 << "K2" << cv::Mat(rig.k2) << "D2" << rig.d2 << "R"
         << cv::Mat(rig.r);
  }
  std::string message = ErrorFrom([&] { prepare::LoadStereoCalibration({dir / "no_t.yaml"}); });
  EXPECT_NE(message.find("no_t.yaml: no 'T'"), std::string::npos) << message;

  rig.r = cv::Matx33d(1, 0, 0, 0, 1, 0, 0, 0, -1);
  prepare::WriteStereoCalibration(dir / "mirror.yaml", rig);
  message = ErrorFrom([&] { prepare::LoadStereoCalibration({dir / "mirror.yaml"}); });
  EXPECT_NE(message.find("mirror.yaml: R is not a rotation"), std::string::npos) << message;

  rig = Rig();
  rig.d1 = cv::Mat::zeros(1, 3, CV_64F);
  prepare::WriteStereoCalibration(dir / "short_d.yaml", rig);
  message = ErrorFrom([&] { prepare::LoadStereoCalibration({dir / "short_d.yaml"}); });
  EXPECT_NE(message.find("short_d.yaml: D1 must hold 4, 5, 8, 12 or 14"), std::string::npos) << message;
  // A coefficient written as a NaN is named (it was "must hold 4, 5, 8, 12 or 14 finite coefficients
  // ..., found 1x5" of a 1x5; OpenCV's own ".Nan" is refused as not a number when read).
  rig = Rig();
  prepare::WriteStereoCalibration(dir / "nan_d.yaml", rig);
  std::string text = ReadBytes(dir / "nan_d.yaml");
  const auto d2 = text.find("data:", text.find("D2:"));
  text.replace(d2, text.find(']', d2) - d2, "data: [ 0., 0., nan, 0., 0. ");
  WriteBytes(dir / "nan_d.yaml", text);
  message = ErrorFrom([&] { prepare::LoadStereoCalibration({dir / "nan_d.yaml"}); });
  EXPECT_NE(message.find("nan_d.yaml: D2's coefficient 3 of 5 is not a finite number"), std::string::npos)
      << message << "\n"
      << text;

  WriteBytes(dir / "junk.yaml", "%YAML:1.0\nK1: [unclosed\n");
  ErrorFrom([&] { prepare::LoadStereoCalibration({dir / "junk.yaml"}); });
  WriteBytes(dir / "bad_ros.yaml", "image_width: 640\nimage_height: 512\n");
  message = ErrorFrom([&] { prepare::LoadStereoCalibration({dir / "bad_ros.yaml", dir / "bad_ros.yaml"}); });
  EXPECT_NE(message.find("bad_ros.yaml: not a ROS camera_info YAML"), std::string::npos) << message;
  ErrorFrom([&] { prepare::LoadStereoCalibration({dir / "absent.yaml"}); }, ErrorCode::kNotFound);
  // A folder is no calibration file (it was "calibration file does not exist", NOT_FOUND).
  message = ErrorFrom([&] { prepare::LoadStereoCalibration({dir.path()}); });
  EXPECT_NE(message.find(": a folder, not a calibration file"), std::string::npos) << message;

  // Found by tests/fuzz/stereo_calibration_fuzz.cc: OpenCV 4.6's parser threw std::length_error on
  // this file, which escaped as no endorecon error.
  WriteBytes(dir / "length.yaml", "%YAML:1.\n   o:3\n   :\n");
  ErrorFrom([&] { prepare::LoadStereoCalibration({dir / "length.yaml"}); });

  // Found by tests/fuzz/stereo_calibration_fuzz.cc: a ROS matrix given as a scalar made yaml-cpp
  // throw from operator[].
  WriteBytes(dir / "scalar_ros.yaml", "image_width: 640\nimage_height: 512\ncamera_matrix: 3\n");
  message = ErrorFrom([&] { prepare::LoadStereoCalibration({dir / "scalar_ros.yaml", dir / "scalar_ros.yaml"}); });
  EXPECT_NE(message.find("scalar_ros.yaml: 'camera_matrix' is missing"), std::string::npos) << message;

  // Found by tests/fuzz/stereo_calibration_fuzz.cc: OpenCV allocated a declared size of 10^9 rows
  // before reading the data (gigabytes); such a size is refused before anything is allocated.
  WriteBytes(dir / "huge.yaml",
             "%YAML:1.0\n---\nK1: !!opencv-matrix\n   rows: 1000000000\n   cols: 3\n   dt: d\n"
             "   data: [ 1., 0., 0. ]\n");
  message = ErrorFrom([&] { prepare::LoadStereoCalibration({dir / "huge.yaml"}); });
  EXPECT_NE(message.find("huge.yaml: 'K1' must declare rows and cols between 1 and 16"), std::string::npos)
      << message;
}

TEST(StereoCalibrationTest, ACalibrationForAnotherSizeIsRefused) {
  const prepare::StereoCalibration rig = Rig();
  prepare::CheckCalibrationFits(rig, {640, 512});
  const std::string message = ErrorFrom([&] { prepare::CheckCalibrationFits(rig, {1280, 1024}); });
  EXPECT_NE(message.find("the calibration is for 640x512 images but the recording's eyes are 1280x1024"),
            std::string::npos)
      << message;
  // As many pixels in another shape: the layout flag of the other kind, or a rotated video.
  const std::string reshaped = ErrorFrom([&] { prepare::CheckCalibrationFits(rig, {1280, 256}); });
  EXPECT_NE(
      reshaped.find("(as many pixels in another shape: is the recording's layout the other one, "
                    "--side-by-side or --top-bottom, or is the video turned by a rotation in its file?)"),
      std::string::npos)
      << reshaped;
  prepare::StereoCalibration unsized = rig;
  unsized.image_size = {};
  prepare::CheckCalibrationFits(unsized, {640, 512});
  ErrorFrom([&] { prepare::CheckCalibrationFits(unsized, {320, 256}); });
  // Twice the size: the principal point inside the frame but at a quarter of it.
  const std::string quarter = ErrorFrom([&] { prepare::CheckCalibrationFits(unsized, {1280, 1024}); });
  EXPECT_NE(quarter.find("lies 15% of the frame or more from the centre of the recording's 1280x1024 eyes"),
            std::string::npos)
      << quarter;
}

TEST(StereoCalibrationTest, RectifiedCalibrationCentresThePrincipalPoint) {
  const prepare::StereoCalibration c = prepare::RectifiedCalibration({640, 512}, 570, 4.5);
  EXPECT_EQ(c.k1(0, 2), 319.5);
  EXPECT_EQ(c.k1(1, 2), 255.5);
  EXPECT_DOUBLE_EQ(c.baseline(), 4.5);
  ErrorFrom([&] { prepare::RectifiedCalibration({640, 512}, 0, 4.5); });
  ErrorFrom([&] { prepare::RectifiedCalibration({640, 512}, 570, -1); });
}

}  // namespace
}  // namespace endorecon::testing
