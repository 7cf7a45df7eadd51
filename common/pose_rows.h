// The cameras of an EndoNeRF clip, read from its poses_bounds.npy and checked row by row: one reader
// for the worker's loader (worker/engine/scene/endonerf_loader.h), which builds its cameras from the
// rows, and for the CLI, which refuses a bad row before the upload (client/clip_check.h).
#pragma once

#include <filesystem>
#include <vector>

namespace endorecon {

// One row: the LLFF pose [down, right, back | t] turned into OpenGL axes [right, up, back | t].
struct PoseRow {
  double c2w[12] = {};  // 3 x 4, column by column (Eigen's order)
  double focal = 0;     // pixels, at width x height
  int width = 0, height = 0;
  double near = 0, far = 0;
};

struct PoseRows {
  std::vector<PoseRow> rows;
  double near = 0, far = 0;  // over all rows
};

// Reads `path` (N x 17 of finite values: common/clip_files.h's PoseRowCount) and checks each row:
// H and W positive integers (at most 1e6) and alike in every row, the camera (principal point at the
// centre) and pose by common/camera_values.h, its near and far, and the bounds over all rows. Throws
// FailInvalid naming the file and the row.
PoseRows ReadPoseRows(const std::filesystem::path& path);
// The same, of the array already read from `path` (named in errors).
struct NpyArray;
PoseRows PoseRowsOf(const NpyArray& array, const std::filesystem::path& path);

}  // namespace endorecon
