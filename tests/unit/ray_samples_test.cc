#include "worker/engine/render/ray_samples.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <vector>

namespace endorecon::render {
namespace {

TEST(RaySamples, SortAscendingSortsWithDuplicates) {
  std::vector<double> v = {3, 1, 2, 5, 1, 0, 4, 2};
  std::vector<double> expected = v;
  std::sort(expected.begin(), expected.end());
  SortAscending(v.data(), static_cast<int>(v.size()));
  EXPECT_EQ(v, expected);
}

TEST(RaySamples, MidpointIntervalsMirrorTheEnds) {
  // Samples 2, 3, 5 in [0, 10]: edges 1.5 | 2.5 | 4 | 6.
  const double s[3] = {2, 3, 5};
  double delta[3];
  MidpointIntervals(s, 3, 0.0, 10.0, delta);
  EXPECT_DOUBLE_EQ(delta[0], 1.0);
  EXPECT_DOUBLE_EQ(delta[1], 1.5);
  EXPECT_DOUBLE_EQ(delta[2], 2.0);
}

TEST(RaySamples, MidpointIntervalsClipToTheRange) {
  // Mirrored ends would be -1 and 12: clipped to 0 and 10.
  const double s[2] = {1, 7};
  double delta[2];
  MidpointIntervals(s, 2, 0.0, 10.0, delta);
  EXPECT_DOUBLE_EQ(delta[0], 4.0);
  EXPECT_DOUBLE_EQ(delta[1], 6.0);
  const double single = 3;
  MidpointIntervals(&single, 1, 2.0, 8.0, delta);
  EXPECT_DOUBLE_EQ(delta[0], 6.0);
}

TEST(RaySamples, CoincidentSamplesGetZeroLengthIntervals) {
  const double s[4] = {5, 5, 5, 6};
  double delta[4];
  MidpointIntervals(s, 4, 0.0, 10.0, delta);
  EXPECT_DOUBLE_EQ(delta[0], 0.0);
  EXPECT_DOUBLE_EQ(delta[1], 0.0);
  EXPECT_DOUBLE_EQ(delta[2], 0.5);
  EXPECT_DOUBLE_EQ(delta[3], 1.0);
}

}  // namespace
}  // namespace endorecon::render
