#include "worker/engine/field/frequency_encoding.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "tests/unit/gradient_check.h"

namespace endorecon::field {
namespace {

TEST(FrequencyEncoding, MatchesTheFormula) {
  const double x[3] = {0.1, 0.5, 0.9};
  constexpr int kL = 3;
  std::vector<double> out(FrequencyEncodingDim(kL));
  ASSERT_EQ(out.size(), 21u);
  FrequencyEncode(x, kL, out.data());
  for (int c = 0; c < 3; ++c) EXPECT_EQ(out[c], x[c]);
  for (int k = 0; k < kL; ++k) {
    for (int c = 0; c < 3; ++c) {
      const double a = std::pow(2.0, k) * M_PI * x[c];
      EXPECT_NEAR(out[3 + 6 * k + c], std::sin(a), 1e-15);
      EXPECT_NEAR(out[3 + 6 * k + 3 + c], std::cos(a), 1e-15);
    }
  }
}

TEST(FrequencyEncoding, BackwardMatchesCentralDifferences) {
  constexpr int kL = 10;
  const auto w = testing::RandomValues(FrequencyEncodingDim(kL), -1, 1, 3);
  std::vector<double> x = {0.23, 0.61, 0.87}, out(w.size());
  const auto loss = [&] {
    FrequencyEncode(x.data(), kL, out.data());
    return testing::Dot(w, out);
  };
  double dx[3];
  FrequencyEncodeBackward(x.data(), kL, w.data(), dx);
  // The finest frequency is 2^9 pi: a small step keeps the difference exact enough.
  testing::ExpectGradientMatches(x.data(), dx, {0, 1, 2}, loss, "x", {1e-7, 1e-6, 1e-7});
}

}  // namespace
}  // namespace endorecon::field
