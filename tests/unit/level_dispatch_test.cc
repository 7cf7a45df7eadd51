#include "worker/engine/field/level_dispatch.h"

#include <gtest/gtest.h>

#include "common/error.h"

namespace endorecon::field {
namespace {

TEST(LevelDispatch, EachSupportedShapeGetsItsInstantiation) {
  for (int features : {1, 2, 4, 8}) {
    for (std::uint32_t dense : {0u, 1u}) {
      GridLevel level;
      level.dense = dense;
      int seen_f = 0;
      bool seen_dense = !dense;
      DispatchLevel(features, level, [&](auto f, auto d) {
        seen_f = decltype(f)::value;
        seen_dense = decltype(d)::value;
      });
      EXPECT_EQ(seen_f, features);
      EXPECT_EQ(seen_dense, dense == 1u);
    }
  }
}

// The CPU grid and the CUDA kernels share this dispatch, so neither reads any other width as 8.
TEST(LevelDispatch, OtherFeatureCountsAreRefused) {
  for (int features : {0, 3, 5, 16}) {
    EXPECT_THROW(DispatchLevel(features, GridLevel{}, [](auto, auto) {}), Error) << features;
  }
}

}  // namespace
}  // namespace endorecon::field
