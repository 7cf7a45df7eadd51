// How far two fields' parameters (or gradients) are apart, for the GPU tests that compare a GPU run
// with the CPU's.
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "worker/engine/cuda/device.h"
#include "worker/engine/cuda/device_field.h"
#include "worker/engine/field/field.h"

namespace endorecon::cuda {

// The largest difference of a block's values, relative to the block's largest magnitude (at least
// 1e-3), and how many values differ by more than `tolerance` of that scale.
struct BlockDifference {
  std::string name;
  double relative = 0;
  std::size_t off = 0, size = 0;
};

inline BlockDifference Difference(const std::string& name, const float* a, const float* b, std::size_t n,
                                  double tolerance) {
  double diff = 0, scale = 1e-3;
  for (std::size_t i = 0; i < n; ++i) scale = std::fmax(scale, std::fabs(double(b[i])));
  BlockDifference d{name, 0, 0, n};
  for (std::size_t i = 0; i < n; ++i) {
    const double e = std::fabs(double(a[i]) - b[i]);
    diff = std::fmax(diff, e);
    d.off += e > tolerance * scale;
  }
  d.relative = diff / scale;
  return d;
}

// The largest difference of two arrays relative to b's largest magnitude (at least 1e-3).
inline double RelativeDifference(const std::vector<float>& a, const std::vector<float>& b) {
  return Difference("", a.data(), b.data(), b.size(), 0).relative;
}

// Block by block, the values of two host fields.
inline std::vector<BlockDifference> Differences(const field::Field& a, const field::Field& b,
                                                double tolerance) {
  std::vector<BlockDifference> out;
  const auto ab = a.Blocks();
  const auto bb = b.Blocks();
  for (std::size_t k = 0; k < ab.size(); ++k)
    out.push_back(Difference(ab[k].name, ab[k].value, bb[k].value, ab[k].size, tolerance));
  return out;
}

// Every block's gradient on the device agrees with the host field's to 1e-3 of the block's largest
// gradient (float rounding: the GPU's atomics add in another order).
inline void ExpectSameGradients(const field::Field& cpu, DeviceField& gpu) {
  const auto host = cpu.Blocks();
  const auto device = gpu.Blocks();
  ASSERT_EQ(host.size(), device.size());
  for (std::size_t k = 0; k < host.size(); ++k) {
    std::vector<float> g(device[k].size);
    CopyToHost(g.data(), device[k].grad, g.size() * sizeof(float));
    const BlockDifference d = Difference(host[k].name, g.data(), host[k].grad, host[k].size, 1e-3);
    EXPECT_LT(d.relative, 1e-3) << "gradient of " << d.name;
  }
}

}  // namespace endorecon::cuda
