#include "server/idle_trim.h"

#include <gtest/gtest.h>

namespace endorecon::server {
namespace {

using std::chrono::seconds;

TEST(IdleTrimTest, TrimsOnceAfterABurstHasBeenQuietNeverDuringIt) {
  IdleTrim trim(seconds(2));
  const auto start = IdleTrim::Clock::now();
  EXPECT_FALSE(trim.Tick(start + seconds(10))) << "nothing arrived: nothing to give back";
  trim.Received(4 << 20);
  EXPECT_FALSE(trim.Tick(IdleTrim::Clock::now())) << "bytes are still arriving";
  EXPECT_FALSE(trim.Tick(IdleTrim::Clock::now() + seconds(1)));
  EXPECT_TRUE(trim.Tick(IdleTrim::Clock::now() + seconds(3)));
  EXPECT_FALSE(trim.Tick(IdleTrim::Clock::now() + seconds(60))) << "once per burst";
  trim.Received(0);
  EXPECT_FALSE(trim.Tick(IdleTrim::Clock::now() + seconds(60))) << "an empty chunk is no burst";
  trim.Received(1);
  EXPECT_TRUE(trim.Tick(IdleTrim::Clock::now() + seconds(3)));
}

}  // namespace
}  // namespace endorecon::server
