// Per-frame camera-to-world poses of the recording's (raw) left eye, e.g. from robot kinematics,
// one per frame of the recording, in the calibration's length unit:
//   JSON  {"convention": "opencv" | "opengl", "poses": [M0, M1, ...]}, each M a 4x4 (or 3x4) array
//         of rows; "convention" says the camera axes (OpenCV: x right, y down, z forward, the
//         default; OpenGL: x right, y up, z back);
//   CSV   one frame per line: 12 (3x4) or 16 (4x4) comma-separated numbers, row-major; blank
//         lines and lines starting with '#' are skipped; OpenCV axes.
// See docs/formats.md ("Pose files").
#pragma once

#include <filesystem>
#include <opencv2/core.hpp>
#include <vector>

namespace endorecon::prepare {

// The poses in OpenCV axes. Throws Error(kNotFound) when the file is missing and
// Error(kInvalidArgument) naming the file and the frame (and the CSV line) for anything else: bad
// JSON or numbers, a wrong shape, a last row other than [0, 0, 0, 1], non-finite values, a rotation
// that is not orthonormal (within 1e-3) or is a reflection.
std::vector<cv::Matx44d> ReadPoseFile(const std::filesystem::path& path);

}  // namespace endorecon::prepare
