// One camera from a transforms.json-style frame object: per-frame intrinsics (fl_x/fl_y or
// camera_angle_x/camera_angle_y, cx, cy) override the top level's; transform_matrix is a 4x4
// camera-to-world in the OpenGL convention. Shared by the transforms.json loader and camera lists.
#pragma once

#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "worker/engine/scene/camera.h"

namespace endorecon::scene {

// A finite number under `key`, or nothing when absent; throws FailInvalid naming `where` otherwise.
std::optional<double> OptionalNumber(const nlohmann::json& object, const char* key, const std::string& where);

// The per-frame value if present, else the top-level one.
std::optional<double> FrameOrTopNumber(const nlohmann::json& frame, const nlohmann::json& top, const char* key,
                                       const std::string& where, const std::string& top_where);

Eigen::Matrix<double, 3, 4> ReadTransform(const nlohmann::json& frame, const std::string& where);

// Builds and validates (CheckCamera) the camera of `frame` for a width x height image.
Camera CameraFromJson(const nlohmann::json& frame, const nlohmann::json& top, int width, int height,
                      const std::string& where, const std::string& top_where);

}  // namespace endorecon::scene
