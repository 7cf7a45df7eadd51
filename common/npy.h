// NumPy .npy files: the pose files of the EndoNeRF layout, float depth maps, and the exports.
#pragma once

#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

namespace endorecon {

struct NpyArray {
  std::vector<std::size_t> shape;  // C order; empty for a 0-d array
  std::vector<double> data;        // product(shape) values, row-major
  std::string dtype;               // the descr found in the file, e.g. "<f8"

  std::size_t size() const { return data.size(); }
};

// Reads a .npy file of format version 1, 2 or 3 holding a C-order little-endian '<f4' or '<f8'
// array ('|u1' is accepted too). Values are widened to double. Anything else (a bad magic string
// or header, Fortran order, big-endian or other dtypes, too few or too many data bytes) throws
// FailInvalid naming the file and what was found.
NpyArray ReadNpy(const std::filesystem::path& path);

// Writes a C-order '<f4' array of product(shape) values as a version 1.0 .npy file whose header
// is padded to a multiple of 64 bytes. Throws Error(kUnavailable) when the file cannot be written.
void WriteNpyFloat32(const std::filesystem::path& path, const float* data,
                     const std::vector<std::size_t>& shape);

// The same for '<f8' (pose files).
void WriteNpyFloat64(const std::filesystem::path& path, const double* data,
                     const std::vector<std::size_t>& shape);

}  // namespace endorecon
