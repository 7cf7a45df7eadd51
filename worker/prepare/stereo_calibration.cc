#include "worker/prepare/stereo_calibration.h"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <set>

#include "common/error.h"
#include "common/file_read.h"
#include "worker/prepare/opencv_storage.h"

namespace endorecon::prepare {
namespace {

namespace fs = std::filesystem;

std::string ShapeText(const cv::Mat& m) { return std::to_string(m.rows) + "x" + std::to_string(m.cols); }

bool AllFinite(const cv::Mat& m) { return cv::checkRange(m, true, nullptr, -1e12, 1e12); }

cv::Matx33d CameraMatrix(const cv::Mat& m, const std::string& where) {
  if (m.rows != 3 || m.cols != 3) FailInvalid(where + " must be a 3x3 matrix, found " + ShapeText(m));
  cv::Matx33d k(m);
  if (!AllFinite(m) || !(k(0, 0) > 0) || !(k(1, 1) > 0) || k(2, 0) != 0 || k(2, 1) != 0 || k(2, 2) != 1) {
    FailInvalid(where + " must be a camera matrix [fx 0 cx; 0 fy cy; 0 0 1] with finite fx, fy > 0");
  }
  return k;
}

cv::Mat Distortion(const cv::Mat& m, const std::string& where) {
  static const std::set<int> kLengths = {4, 5, 8, 12, 14};
  if (std::min(m.rows, m.cols) != 1 || !kLengths.count(m.rows * m.cols)) {
    FailInvalid(where + " must hold 4, 5, 8, 12 or 14 coefficients (OpenCV's model), found " + ShapeText(m));
  }
  cv::Mat d;
  m.reshape(1, 1).convertTo(d, CV_64F);
  for (int i = 0; i < d.cols; ++i) {
    if (!std::isfinite(d.at<double>(0, i)) || std::abs(d.at<double>(0, i)) > 1e12)
      FailInvalid(where + "'s coefficient " + std::to_string(i + 1) + " of " + std::to_string(d.cols) +
                  " is not a finite number");
  }
  return d;
}

cv::Matx33d Rotation(const cv::Mat& m, const std::string& where) {
  if (m.rows != 3 || m.cols != 3 || !AllFinite(m))
    FailInvalid(where + " must be a finite 3x3 rotation matrix");
  const cv::Matx33d r(m);
  const double off = cv::norm(r.t() * r - cv::Matx33d::eye(), cv::NORM_INF);
  if (off > 1e-3 || cv::determinant(r) < 0) {
    FailInvalid(where + " is not a rotation (max |R^T R - I| = " + std::to_string(off) + ", det " +
                std::to_string(cv::determinant(r)) + ")");
  }
  return r;
}

cv::Vec3d Translation(const cv::Mat& m, const std::string& where) {
  if (m.rows * m.cols != 3 || !AllFinite(m))
    FailInvalid(where + " must hold 3 finite numbers, found " + ShapeText(m));
  cv::Mat t;
  m.reshape(1, 3).convertTo(t, CV_64F);
  const cv::Vec3d v(t);
  if (!(cv::norm(v) > 0)) FailInvalid(where + " is zero: the eyes must be apart");
  return v;
}

cv::Mat ReadMatrix(const OpenCvStorage& file, const std::string& name,
                   std::initializer_list<const char*> keys) {
  for (const char* key : keys) {
    if (std::optional<cv::Mat> m = file.Matrix(key)) return *m;
  }
  FailInvalid(name + ": no '" + *keys.begin() +
              "' (an OpenCV stereo calibration holds K1 D1 K2 D2 R T; see docs/formats.md)");
}

// image_width/image_height, or image_size/imageSize as [w, h]; 0x0 if absent.
cv::Size ReadSize(const OpenCvStorage& file, const std::string& name) {
  cv::Size size;
  if (file.Has("image_width") || file.Has("image_height")) {
    const auto width = file.Ints("image_width"), height = file.Ints("image_height");
    if (!width || !height || width->size() != 1 || height->size() != 1)
      FailInvalid(name + ": 'image_width' and 'image_height' must be given together, a whole number each");
    size = {width->front(), height->front()};
  } else {
    for (const char* key : {"image_size", "imageSize"}) {
      const auto wh = file.Ints(key);
      if (!wh) continue;
      if (wh->size() != 2) FailInvalid(name + ": '" + key + "' must be [width, height]");
      size = {(*wh)[0], (*wh)[1]};
    }
  }
  if (size != cv::Size() && (size.width < 1 || size.height < 1))
    FailInvalid(name + ": the image size must be positive, found " + std::to_string(size.width) + "x" +
                std::to_string(size.height));
  return size;
}

StereoCalibration LoadOpenCv(const fs::path& path) {
  const std::string name = path.string();
  const OpenCvStorage file = OpenCvStorage::Load(path);
  StereoCalibration c;
  c.source = name;
  c.kind = "opencv";
  c.image_size = ReadSize(file, name);
  c.k1 = CameraMatrix(ReadMatrix(file, name, {"K1", "M1"}), name + ": K1");
  c.d1 = Distortion(ReadMatrix(file, name, {"D1"}), name + ": D1");
  c.k2 = CameraMatrix(ReadMatrix(file, name, {"K2", "M2"}), name + ": K2");
  c.d2 = Distortion(ReadMatrix(file, name, {"D2"}), name + ": D2");
  c.r = Rotation(ReadMatrix(file, name, {"R"}), name + ": R");
  c.t = Translation(ReadMatrix(file, name, {"T"}), name + ": T");
  return c;
}

// One ROS camera_info YAML (camera_calibration_parsers' format).
struct RosCameraInfo {
  cv::Size size;
  cv::Mat k, d, r, p;
};

cv::Mat RosMatrix(const YAML::Node& top, const char* key, int rows, int cols, const std::string& name) {
  const YAML::Node node = top[key];
  const std::string where = name + ": '" + key + "'";
  // A node that is not a map throws on operator[] (tests/fuzz/stereo_calibration_fuzz.cc found it).
  if (!node || !node.IsMap() || !node["data"] || !node["data"].IsSequence())
    FailInvalid(where + " is missing (or has no 'data' list)");
  const YAML::Node data = node["data"];
  if (cols > 0 && data.size() != static_cast<std::size_t>(rows * cols)) {
    FailInvalid(where + " must hold " + std::to_string(rows * cols) + " numbers, found " +
                std::to_string(data.size()));
  }
  cv::Mat m(1, static_cast<int>(data.size()), CV_64F);
  for (std::size_t i = 0; i < data.size(); ++i) {
    try {
      m.at<double>(0, static_cast<int>(i)) = data[i].as<double>();
    } catch (const YAML::Exception&) {
      FailInvalid(where + " entry " + std::to_string(i) + " is not a number");
    }
  }
  return cols > 0 ? m.reshape(1, rows) : m;
}

RosCameraInfo LoadRos(const fs::path& path) {
  RequireExistingFile(path, "calibration file");
  const std::string name = path.string();
  YAML::Node top;
  try {
    top = YAML::LoadFile(name);
  } catch (const YAML::Exception& e) {
    FailInvalid(name + ": not valid YAML (" + e.what() + ")");
  }
  if (!top.IsMap() || !top["camera_matrix"]) {
    FailInvalid(name +
                ": not a ROS camera_info YAML (no 'camera_matrix'); an OpenCV stereo calibration is "
                "given as one file");
  }
  RosCameraInfo info;
  try {
    info.size = {top["image_width"].as<int>(), top["image_height"].as<int>()};
  } catch (const YAML::Exception&) {
    FailInvalid(name + ": 'image_width' and 'image_height' must be whole numbers");
  }
  std::string model = "plumb_bob";
  if (const YAML::Node node = top["distortion_model"]) {
    if (!node.IsScalar())
      FailInvalid(name + ": 'distortion_model' must be a name (plumb_bob or rational_polynomial)");
    model = node.as<std::string>();
  }
  if (model != "plumb_bob" && model != "rational_polynomial") {
    FailInvalid(
        name + ": distortion_model '" + model +
        "' is not supported (plumb_bob or rational_polynomial; convert fisheye/equidistant models first)");
  }
  info.k = RosMatrix(top, "camera_matrix", 3, 3, name);
  info.d = RosMatrix(top, "distortion_coefficients", 1, 0, name);
  info.r = RosMatrix(top, "rectification_matrix", 3, 3, name);
  info.p = RosMatrix(top, "projection_matrix", 3, 4, name);
  return info;
}

// ROS keeps each eye's rectifying rotation R_i and the rectified right projection P2, whose
// P2(0, 3) = -f' B. In the rectified frame the right eye sits at (B, 0, 0), so
// X_right = R2^T (R1 X_left - (B, 0, 0)): R = R2^T R1, T = -R2^T (B, 0, 0).
StereoCalibration LoadRosPair(const fs::path& left_path, const fs::path& right_path) {
  const RosCameraInfo left = LoadRos(left_path), right = LoadRos(right_path);
  const std::string name = right_path.string();
  if (left.size != right.size) {
    FailInvalid(name + ": image size " + std::to_string(right.size.width) + "x" +
                std::to_string(right.size.height) + " differs from " + left_path.string() + "'s");
  }
  StereoCalibration c;
  c.source = left_path.string() + " + " + right_path.string();
  c.kind = "ros";
  c.image_size = left.size;
  c.k1 = CameraMatrix(left.k, left_path.string() + ": camera_matrix");
  c.k2 = CameraMatrix(right.k, name + ": camera_matrix");
  c.d1 = Distortion(left.d, left_path.string() + ": distortion_coefficients");
  c.d2 = Distortion(right.d, name + ": distortion_coefficients");
  const cv::Matx33d r1 = Rotation(left.r, left_path.string() + ": rectification_matrix");
  const cv::Matx33d r2 = Rotation(right.r, name + ": rectification_matrix");
  const double f = right.p.at<double>(0, 0), tx = right.p.at<double>(0, 3);
  if (!(f > 0) || !std::isfinite(tx) || tx == 0) {
    FailInvalid(
        name +
        ": projection_matrix must have fx > 0 and P[0][3] = -fx * baseline != 0 (is this the right eye?)");
  }
  const cv::Vec3d offset(-tx / f, 0, 0);
  c.r = r2.t() * r1;
  c.t = -(r2.t() * offset);
  return c;
}

}  // namespace

StereoCalibration LoadStereoCalibration(const std::vector<fs::path>& files) {
  if (files.size() == 1) return LoadOpenCv(files[0]);
  if (files.size() == 2) return LoadRosPair(files[0], files[1]);
  FailInvalid(
      "--calibration takes one OpenCV stereo calibration file or two ROS camera_info YAMLs (left, "
      "right), got " +
      std::to_string(files.size()) + " files");
}

StereoCalibration RectifiedCalibration(cv::Size size, double focal, double baseline) {
  if (!(focal > 0) || !std::isfinite(focal))
    FailInvalid("--focal must be a finite focal length > 0 (pixels)");
  if (!(baseline > 0) || !std::isfinite(baseline)) FailInvalid("--baseline must be a finite distance > 0");
  StereoCalibration c;
  c.source = "--rectified --focal " + std::to_string(focal) + " --baseline " + std::to_string(baseline);
  c.kind = "rectified";
  c.image_size = size;
  c.k1 = c.k2 = cv::Matx33d(focal, 0, size.width / 2.0 - 0.5, 0, focal, size.height / 2.0 - 0.5, 0, 0, 1);
  c.d1 = c.d2 = cv::Mat::zeros(1, 5, CV_64F);
  c.r = cv::Matx33d::eye();
  c.t = cv::Vec3d(-baseline, 0, 0);
  return c;
}

void CheckCalibrationFits(const StereoCalibration& c, cv::Size eye_size) {
  const auto text = [](cv::Size s) { return std::to_string(s.width) + "x" + std::to_string(s.height); };
  if (c.image_size != cv::Size()) {
    if (c.image_size != eye_size) {
      // The same pixels in another shape: a layout flag of the other kind, or a video turned by its
      // container's rotation tag, rather than another calibration (found 2026-12-06).
      const bool reshaped = c.image_size.area() == eye_size.area();
      FailInvalid(c.source + ": the calibration is for " + text(c.image_size) +
                  " images but the recording's eyes are " + text(eye_size) +
                  (reshaped ? " (as many pixels in another shape: is the recording's layout the other one, "
                              "--side-by-side or --top-bottom, or is the video turned by a rotation in its "
                              "file?)"
                            : " (calibrate at the recording's size)"));
    }
    return;
  }
  // A lens's principal point lies near its image's centre (a few per cent off); one 15% of the frame
  // or more away is a calibration of another size (one for 160x128 taken for 320x256 eyes, its
  // principal point at a quarter of them, prepared a corner without a word; found 2026-12-06).
  constexpr double kMostCentreOffset = 0.15;
  for (const cv::Matx33d& k : {c.k1, c.k2}) {
    if (std::abs(k(0, 2) - eye_size.width / 2.0) > kMostCentreOffset * eye_size.width ||
        std::abs(k(1, 2) - eye_size.height / 2.0) > kMostCentreOffset * eye_size.height) {
      FailInvalid(c.source + ": the principal point (" + std::to_string(k(0, 2)) + ", " +
                  std::to_string(k(1, 2)) +
                  ") lies 15% of the frame or more from the centre of the "
                  "recording's " +
                  text(eye_size) +
                  " eyes: the calibration is for another image size (it names none; add image_width and "
                  "image_height)");
    }
  }
}

void WriteStereoCalibration(const fs::path& path, const StereoCalibration& c,
                            const std::vector<std::pair<std::string, double>>& extra) {
  cv::FileStorage file;
  try {
    file.open(path.string(), cv::FileStorage::WRITE);
  } catch (const cv::Exception&) {
  }
  if (!file.isOpened()) Fail(ErrorCode::kUnavailable, "cannot write " + path.string());
  file << "image_width" << c.image_size.width << "image_height" << c.image_size.height;
  file << "K1" << cv::Mat(c.k1) << "D1" << c.d1 << "K2" << cv::Mat(c.k2) << "D2" << c.d2;
  file << "R" << cv::Mat(c.r) << "T" << cv::Mat(c.t);
  for (const auto& [key, value] : extra) file << key << value;
}

}  // namespace endorecon::prepare
