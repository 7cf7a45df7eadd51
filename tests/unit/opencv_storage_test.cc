// OpenCV FileStorage files read without OpenCV's parser: what cv::FileStorage writes reads back
// exactly, in YAML and XML, and what it crashed on is refused with a message naming the file.
#include "worker/prepare/opencv_storage.h"

#include <gtest/gtest.h>

#include "tests/unit/clip_fixture.h"
#include "tests/unit/temp_dir.h"

namespace endorecon::testing {
namespace {

TEST(OpenCvStorageTest, ReadsWhatCvFileStorageWritesInYamlAndXml) {
  TempDir dir("storage");
  const cv::Mat k = (cv::Mat_<double>(2, 3) << 512.25, 0, 319.5, -1e-300, 6.02e23, 1);
  const cv::Mat t(1, 1, CV_64FC3, cv::Scalar(-4.5, 0.125, 3));
  const cv::Mat f = (cv::Mat_<float>(1, 2) << 0.1f, -2.5f);
  for (const char* name : {"s.yaml", "s.xml", "s.yml"}) {
    {
      cv::FileStorage out((dir / name).string(), cv::FileStorage::WRITE);
      out << "width" << 640 << "size" << std::vector<int>{640, 512} << "K" << k << "T" << t << "F" << f;
      out << "note"
          << "free text";
    }
    const prepare::OpenCvStorage storage = prepare::OpenCvStorage::Load(dir / name);
    EXPECT_EQ(storage.Ints("width"), std::vector<int>{640}) << name;
    EXPECT_EQ(storage.Ints("size"), (std::vector<int>{640, 512})) << name;
    EXPECT_FALSE(storage.Ints("absent").has_value());
    EXPECT_FALSE(storage.Matrix("absent").has_value());
    const cv::Mat read_k = *storage.Matrix("K");
    ASSERT_EQ(read_k.size(), k.size()) << name;
    EXPECT_EQ(cv::norm(read_k, k, cv::NORM_INF), 0) << name;  // %.17g text: exact
    const cv::Mat read_t = *storage.Matrix("T");
    EXPECT_EQ(read_t.size(), cv::Size(3, 1)) << name;  // a 1x1 three-channel matrix: 3 numbers
    EXPECT_EQ(read_t.at<double>(0), -4.5);
    EXPECT_NEAR(storage.Matrix("F")->at<double>(1), -2.5, 0) << name;
    const std::string message = ErrorFrom([&] { storage.Matrix("width"); });
    EXPECT_NE(message.find(name + std::string(": 'width' is not a matrix")), std::string::npos) << message;
    ErrorFrom([&] { storage.Ints("note"); });
    ErrorFrom([&] { storage.Ints("K"); });
  }
}

TEST(OpenCvStorageTest, MalformedFilesAreRefusedNamingTheFile) {
  TempDir dir("storage");
  const auto refused = [&](const std::string& file, const std::string& bytes, const std::string& expected) {
    WriteBytes(dir / file, bytes);
    const std::string message = ErrorFrom([&] {
      const prepare::OpenCvStorage storage = prepare::OpenCvStorage::Load(dir / file);
      storage.Matrix("K");
    });
    EXPECT_NE(message.find((dir / file).string() + ": " + expected), std::string::npos) << message;
  };
  // Found by tests/fuzz/stereo_calibration_fuzz.cc: cv::FileStorage::open segfaulted inside OpenCV
  // 4.6 on these two (a truncated XML declaration; a YAML header followed by broken bytes).
  refused("truncated.xml", "<?xml version=", "not well-formed XML");
  refused("broken.yaml",
          std::string("%YAML:1.0\n--\xd3\xd1\xb6\x98"
                      "ag.pencv-m.,",
                      28),
          "not an OpenCV storage file");
  refused("other_root.xml", "<?xml version=\"1.0\"?><calibration><K>1</K></calibration>",
          "not an OpenCV storage file (its XML root is not <opencv_storage>)");
  refused("list.yaml", "%YAML:1.0\n---\n- 1\n- 2\n", "not an OpenCV storage file");
  refused("count.yaml", "%YAML:1.0\n---\nK: !!opencv-matrix\n  rows: 3\n  cols: 3\n  dt: d\n  data: [1, 2]\n",
          "'K' declares 3x3 (d) but its data holds 2 numbers");
  refused("dt.xml",
          "<?xml version=\"1.0\"?><opencv_storage><K type_id=\"opencv-matrix\"><rows>1</rows><cols>1</cols>"
          "<dt>q</dt><data>1</data></K></opencv_storage>",
          "'K' has dt 'q'");
  refused("word.yaml", "K: !!opencv-matrix\n  rows: 1\n  cols: 2\n  dt: d\n  data: [1, one]\n",
          "'K' entry 1 ('one') is not a number");
  refused("huge.yaml", "K: !!opencv-matrix\n  rows: 1000000000\n  cols: 3\n  dt: d\n  data: [1]\n",
          "'K' must declare rows and cols between 1 and 16");
  refused(
      "large.yaml", "K: 1\n" + std::string(prepare::OpenCvStorage::kMaxBytes, '#'),
      std::to_string(prepare::OpenCvStorage::kMaxBytes + 5) + " bytes is too large for a calibration file");
  ErrorFrom([&] { prepare::OpenCvStorage::Load(dir / "absent.yaml"); }, ErrorCode::kNotFound);
}

}  // namespace
}  // namespace endorecon::testing
