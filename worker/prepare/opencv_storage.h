// The top-level fields of a file in OpenCV's FileStorage layout (YAML or XML): scalars, lists of
// numbers and opencv-matrix nodes (rows, cols, dt, data), as stereo calibrations hold them.
//
// Read with yaml-cpp and tinyxml2, not cv::FileStorage: OpenCV 4.6's hand-written parsers crash
// (a null dereference inside libopencv_core) on crafted files, e.g. a truncated "<?xml version="
// (tests/fuzz/stereo_calibration_fuzz.cc), and a crash there took `prepare` down with it. The two
// libraries are fuzzed upstream and bound their nesting depth. Writing stays with cv::FileStorage.
#pragma once

#include <filesystem>
#include <map>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

namespace endorecon::prepare {

class OpenCvStorage {
 public:
  // Files larger than this are refused before they are read: a calibration is a few kilobytes.
  static constexpr std::uintmax_t kMaxBytes = 1 << 20;

  // Throws Error(kNotFound) for a missing file and Error(kInvalidArgument) naming the file for one
  // that is too large, not well-formed YAML/XML, or whose top level is not a map of fields.
  static OpenCvStorage Load(const std::filesystem::path& path);

  bool Has(const std::string& key) const { return fields_.count(key) > 0; }

  // The field `key` as a rows x (cols * channels) CV_64F matrix; nullopt when absent. Throws
  // Error(kInvalidArgument) naming the file and key when it is no opencv-matrix, declares rows or
  // cols outside 1..16, or holds another count of numbers than it declares.
  std::optional<cv::Mat> Matrix(const std::string& key) const;

  // The field `key` as whole numbers (a scalar is a list of one); nullopt when absent. Throws
  // Error(kInvalidArgument) naming the file and key when an entry is not a whole number in int range.
  std::optional<std::vector<int>> Ints(const std::string& key) const;

 private:
  struct Field {
    std::vector<std::string> words;  // a scalar's text, a list's items, or a matrix's data
    bool matrix = false;
    std::string rows, cols, dt;  // as written, for a matrix
  };

  static OpenCvStorage ParseYaml(const std::string& text, const std::string& name);
  static OpenCvStorage ParseXml(const std::string& text, const std::string& name);

  std::string name_;
  std::map<std::string, Field> fields_;
};

}  // namespace endorecon::prepare
