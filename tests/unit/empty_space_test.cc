#include "worker/engine/render/empty_space.h"

#include <gtest/gtest.h>

namespace endorecon::render {
namespace {

TEST(EmptySpace, KeepsOccupiedSamplesInOrder) {
  double s[6] = {1, 2, 3, 4, 5, 6}, delta[6] = {0.1, 0.2, 0.3, 0.4, 0.5, 0.6};
  const uint8_t occupied[6] = {0, 1, 1, 0, 0, 1};
  int source[6];
  const int kept = CompactOccupiedSamples(occupied, 6, s, delta, source);
  ASSERT_EQ(kept, 3);
  const double expected_s[3] = {2, 3, 6}, expected_delta[3] = {0.2, 0.3, 0.6};
  const int expected_source[3] = {1, 2, 5};
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(s[i], expected_s[i]);
    EXPECT_EQ(delta[i], expected_delta[i]);
    EXPECT_EQ(source[i], expected_source[i]);
  }
}

TEST(EmptySpace, AllEmptyKeepsNothing) {
  double s[2] = {1, 2}, delta[2] = {1, 1};
  const uint8_t occupied[2] = {0, 0};
  EXPECT_EQ(CompactOccupiedSamples(occupied, 2, s, delta, static_cast<int*>(nullptr)), 0);
}

}  // namespace
}  // namespace endorecon::render
