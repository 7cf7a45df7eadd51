#include "common/pose_rows.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include "common/camera_values.h"
#include "common/clip_files.h"
#include "common/error.h"
#include "common/npy.h"

namespace endorecon {
namespace {

namespace fs = std::filesystem;

std::string Number(double value) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.9g", value);
  return text;
}

}  // namespace

PoseRows ReadPoseRows(const fs::path& path) {
  if (!fs::exists(path)) FailInvalid(path.string() + ": file does not exist");
  return PoseRowsOf(ReadNpy(path), path);
}

PoseRows PoseRowsOf(const NpyArray& array, const fs::path& path) {
  const std::size_t count = PoseRowCount(array, path);

  PoseRows poses;
  poses.near = INFINITY;
  poses.far = -INFINITY;
  for (std::size_t i = 0; i < count; ++i) {
    const double* values = &array.data[i * kPoseColumns];
    const std::string where = path.string() + " row " + std::to_string(i);
    const double h = values[4], w = values[9], f = values[14];
    if (!(h >= 1 && w >= 1 && h == std::floor(h) && w == std::floor(w) && h <= 1e6 && w <= 1e6)) {
      FailInvalid(where + ": H and W must be positive integers (H = " + Number(h) + ", W = " + Number(w) +
                  ")");
    }
    PoseRow row;
    row.width = static_cast<int>(w);
    row.height = static_cast<int>(h);
    row.focal = f;
    row.near = values[15];
    row.far = values[16];
    // LLFF stores the rotation's columns as [down, right, back]; OpenGL wants [right, up, back].
    for (int r = 0; r < 3; ++r) {
      row.c2w[0 * 3 + r] = values[r * 5 + 1];
      row.c2w[1 * 3 + r] = -values[r * 5 + 0];
      row.c2w[2 * 3 + r] = values[r * 5 + 2];
      row.c2w[3 * 3 + r] = values[r * 5 + 3];
    }
    CheckIntrinsics(f, f, w / 2, h / 2, row.width, row.height, where);
    CheckRigidPose(row.c2w, where);
    if (!poses.rows.empty() && (row.width != poses.rows[0].width || row.height != poses.rows[0].height)) {
      FailInvalid(where + ": image size " + SizeText(row.width, row.height) + " differs from row 0's " +
                  SizeText(poses.rows[0].width, poses.rows[0].height));
    }
    CheckNearFar(row.near, row.far, where);
    poses.near = std::min(poses.near, row.near);
    poses.far = std::max(poses.far, row.far);
    poses.rows.push_back(row);
  }
  CheckNearFar(poses.near, poses.far, path.string() + " (over all rows)");
  return poses;
}

}  // namespace endorecon
