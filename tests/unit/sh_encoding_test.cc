#include "worker/engine/field/sh_encoding.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace endorecon::field {
namespace {

// Integral of Y_i Y_j over the sphere by a product Gauss-free midpoint rule in (cos theta, phi):
// the 16 functions are orthonormal.
TEST(ShEncodingTest, BasisIsOrthonormal) {
  const int nu = 400, nphi = 800;
  std::vector<double> gram(kShDims * kShDims, 0.0);
  double y[kShDims];
  for (int a = 0; a < nu; ++a) {
    const double u = -1 + (a + 0.5) * 2.0 / nu;  // cos theta
    const double s = std::sqrt(1 - u * u);
    for (int b = 0; b < nphi; ++b) {
      const double phi = (b + 0.5) * 2 * M_PI / nphi;
      const double d[3] = {s * std::cos(phi), s * std::sin(phi), u};
      ShEncode(d, y);
      for (int i = 0; i < kShDims; ++i) {
        for (int j = 0; j < kShDims; ++j) gram[i * kShDims + j] += y[i] * y[j];
      }
    }
  }
  const double cell = (2.0 / nu) * (2 * M_PI / nphi);
  for (int i = 0; i < kShDims; ++i) {
    for (int j = 0; j < kShDims; ++j)
      EXPECT_NEAR(gram[i * kShDims + j] * cell, i == j ? 1.0 : 0.0, 1e-4) << i << "," << j;
  }
}

TEST(ShEncodingTest, KnownValuesAlongTheAxes) {
  float y[kShDims];
  const float z[3] = {0, 0, 1};
  ShEncode(z, y);
  EXPECT_FLOAT_EQ(y[0], 0.28209479f);
  EXPECT_FLOAT_EQ(y[2], 0.48860251f);
  EXPECT_FLOAT_EQ(y[6], 0.94617470f - 0.31539157f);
  EXPECT_FLOAT_EQ(y[1], 0.0f);
  EXPECT_FLOAT_EQ(y[12], 0.37317633f * 2);
}

TEST(ShEncodingTest, BatchWritesStridedRows) {
  const std::vector<float> dir = {1, 0, 0, 0, 1, 0};
  std::vector<float> out(2 * 20, -7.0f);
  ShEncodeBatch(dir.data(), 2, out.data(), 20);
  float y[kShDims];
  ShEncode(dir.data() + 3, y);
  for (int i = 0; i < kShDims; ++i) EXPECT_EQ(out[20 + i], y[i]);
  EXPECT_EQ(out[16], -7.0f);  // padding untouched
}

}  // namespace
}  // namespace endorecon::field
