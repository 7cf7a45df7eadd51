#include "worker/engine/scene/camera_json.h"

#include <fmt/format.h>

#include <cmath>
#include <numbers>
#include <string>
#include <utility>

#include "common/error.h"
#include "worker/engine/scene/clip_checks.h"

namespace endorecon::scene {

using json = nlohmann::json;

std::optional<double> OptionalNumber(const json& object, const char* key, const std::string& where) {
  if (!object.contains(key)) return std::nullopt;
  const json& value = object[key];
  if (!value.is_number() || !std::isfinite(value.get<double>())) {
    FailInvalid(where + ": \"" + key + "\" must be a finite number, found " + value.dump());
  }
  return value.get<double>();
}

std::optional<double> FrameOrTopNumber(const json& frame, const json& top, const char* key,
                                       const std::string& where, const std::string& top_where) {
  if (auto value = OptionalNumber(frame, key, where)) return value;
  return OptionalNumber(top, key, top_where);
}

Eigen::Matrix<double, 3, 4> ReadTransform(const json& frame, const std::string& where) {
  if (!frame.contains("transform_matrix")) FailInvalid(where + ": no \"transform_matrix\"");
  const json& m = frame["transform_matrix"];
  const auto bad = [&] { FailInvalid(where + ": \"transform_matrix\" must be 4x4 numbers, found " + m.dump()); };
  if (!m.is_array() || m.size() != 4) bad();
  Eigen::Matrix4d matrix;
  for (int r = 0; r < 4; ++r) {
    if (!m[r].is_array() || m[r].size() != 4) bad();
    for (int c = 0; c < 4; ++c) {
      if (!m[r][c].is_number()) bad();
      matrix(r, c) = m[r][c].get<double>();
    }
  }
  if ((matrix.row(3) - Eigen::RowVector4d(0, 0, 0, 1)).cwiseAbs().maxCoeff() > 1e-6) {
    FailInvalid(where + ": the last row of \"transform_matrix\" must be [0, 0, 0, 1], found " + m[3].dump());
  }
  return matrix.topRows<3>();
}

Camera CameraFromJson(const json& frame, const json& top, int width, int height, const std::string& where,
                      const std::string& file) {
  Camera camera;
  camera.width = width;
  camera.height = height;
  const std::optional<double> fl_x = FrameOrTopNumber(frame, top, "fl_x", where, file);
  const std::optional<double> angle_x = FrameOrTopNumber(frame, top, "camera_angle_x", where, file);
  const std::optional<double> fl_y = FrameOrTopNumber(frame, top, "fl_y", where, file);
  const std::optional<double> angle_y = FrameOrTopNumber(frame, top, "camera_angle_y", where, file);
  // A field of view is an angle in radians between 0 and pi (one in degrees, 60, gave a negative or
  // meaningless focal length); CheckCamera then bounds the view a pinhole camera can have.
  for (const auto& [key, angle] :
       {std::pair{"camera_angle_x", angle_x}, std::pair{"camera_angle_y", angle_y}}) {
    if (angle && !(*angle > 0 && *angle < std::numbers::pi)) {
      FailInvalid(fmt::format("{}: \"{}\" must be an angle in radians between 0 and pi, found {:g}{}", where,
                              key, *angle, *angle >= std::numbers::pi && *angle < 360 ? " (degrees?)" : ""));
    }
  }
  if (fl_x) {
    camera.fx = *fl_x;
  } else if (angle_x) {
    camera.fx = 0.5 * width / std::tan(0.5 * *angle_x);
  } else {
    FailInvalid(where + ": no focal length (give \"fl_x\" or \"camera_angle_x\")");
  }
  camera.fy = fl_y ? *fl_y : angle_y ? 0.5 * height / std::tan(0.5 * *angle_y) : camera.fx;
  camera.cx = FrameOrTopNumber(frame, top, "cx", where, file).value_or(width / 2.0);
  camera.cy = FrameOrTopNumber(frame, top, "cy", where, file).value_or(height / 2.0);
  camera.c2w = ReadTransform(frame, where);
  CheckCamera(camera, where);
  return camera;
}

}  // namespace endorecon::scene
