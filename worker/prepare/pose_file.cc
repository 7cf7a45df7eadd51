#include "worker/prepare/pose_file.h"

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "common/error.h"
#include "common/file_read.h"
#include "common/json_file.h"

namespace endorecon::prepare {
namespace {

namespace fs = std::filesystem;

// Checks a camera-to-world matrix of `values` (12 or 16, row-major) and returns it as 4x4.
cv::Matx44d RigidPose(const std::vector<double>& values, const std::string& where) {
  if (values.size() != 12 && values.size() != 16) {
    FailInvalid(where + ": a pose needs 12 (3x4) or 16 (4x4) numbers, found " +
                std::to_string(values.size()));
  }
  for (double v : values) {
    if (!std::isfinite(v)) FailInvalid(where + ": the pose has non-finite entries");
  }
  cv::Matx44d pose = cv::Matx44d::eye();
  for (int i = 0; i < static_cast<int>(values.size()); ++i)
    pose(i / 4, i % 4) = values[static_cast<std::size_t>(i)];
  if (values.size() == 16 && (pose(3, 0) != 0 || pose(3, 1) != 0 || pose(3, 2) != 0 || pose(3, 3) != 1)) {
    std::ostringstream row;
    row << "[" << pose(3, 0) << ", " << pose(3, 1) << ", " << pose(3, 2) << ", " << pose(3, 3) << "]";
    FailInvalid(where + ": the last row must be [0, 0, 0, 1], found " + row.str() +
                " (not a rigid transform)");
  }
  const cv::Matx33d r = pose.get_minor<3, 3>(0, 0);
  const double off = cv::norm(r.t() * r - cv::Matx33d::eye(), cv::NORM_INF);
  if (off > 1e-3) {
    FailInvalid(where + ": the rotation is not orthonormal (max |R^T R - I| = " + std::to_string(off) +
                "): not a rigid transform");
  }
  if (cv::determinant(r) < 0) FailInvalid(where + ": the rotation has determinant -1 (a reflection)");
  return pose;
}

std::vector<cv::Matx44d> ReadJson(const fs::path& path) {
  const std::string file = path.string();
  const nlohmann::json top = ReadJsonFile(path);
  if (!top.is_object() || !top.contains("poses") || !top["poses"].is_array()) {
    FailInvalid(file + ": expected {\"convention\": \"opencv\"|\"opengl\", \"poses\": [4x4 matrices]}");
  }
  const std::string convention = top.value("convention", std::string("opencv"));
  if (convention != "opencv" && convention != "opengl") {
    FailInvalid(file + ": \"convention\" must be \"opencv\" or \"opengl\", found \"" + convention + "\"");
  }
  std::vector<cv::Matx44d> poses;
  for (std::size_t i = 0; i < top["poses"].size(); ++i) {
    const std::string where = file + " frame " + std::to_string(i);
    const nlohmann::json& rows = top["poses"][i];
    std::vector<double> values;
    if (!rows.is_array()) FailInvalid(where + ": a pose must be an array of rows");
    for (const nlohmann::json& row : rows) {
      if (!row.is_array() || row.size() != 4)
        FailInvalid(where + ": every row of a pose must hold 4 numbers");
      for (const nlohmann::json& v : row) {
        if (!v.is_number()) FailInvalid(where + ": " + v.dump() + " is not a number");
        values.push_back(v.get<double>());
      }
    }
    cv::Matx44d pose = RigidPose(values, where);
    if (convention == "opengl") pose = pose * cv::Matx44d(1, 0, 0, 0, 0, -1, 0, 0, 0, 0, -1, 0, 0, 0, 0, 1);
    poses.push_back(pose);
  }
  return poses;
}

std::vector<cv::Matx44d> ReadCsv(const fs::path& path) {
  std::ifstream in(path);
  if (!in) FailInvalid(path.string() + ": cannot read the file");
  std::vector<cv::Matx44d> poses;
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    const auto first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    const std::string where =
        path.string() + " line " + std::to_string(number) + " (frame " + std::to_string(poses.size()) + ")";
    std::vector<double> values;
    std::stringstream cells(line);
    std::string cell;
    while (std::getline(cells, cell, ',')) {
      std::size_t used = 0;
      double value = 0;
      try {
        value = std::stod(cell, &used);
      } catch (const std::exception&) {
        used = 0;
      }
      if (used == 0 || cell.find_first_not_of(" \t\r", used) != std::string::npos) {
        FailInvalid(where + ": '" + cell + "' is not a number");
      }
      values.push_back(value);
    }
    poses.push_back(RigidPose(values, where));
  }
  return poses;
}

}  // namespace

std::vector<cv::Matx44d> ReadPoseFile(const fs::path& path) {
  RequireExistingFile(path, "pose file");
  std::vector<cv::Matx44d> poses = path.extension() == ".json" ? ReadJson(path) : ReadCsv(path);
  if (poses.empty()) FailInvalid(path.string() + ": holds no pose");
  return poses;
}

}  // namespace endorecon::prepare
