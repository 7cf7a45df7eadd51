// The training clock: the share of the run done (iterations or budget, never backwards when the
// budget is revised), the end (cap 0: none), and the ETA.
#include "worker/engine/train/run_clock.h"

#include <gtest/gtest.h>

namespace endorecon::train {
namespace {

TEST(RunClock, IterationCapAloneOrBudgetWhicheverIsFurther) {
  RunClock capped(100, 0, 0);
  capped.AddStep(1.0, 10);
  EXPECT_DOUBLE_EQ(capped.Progress(25), 0.25);
  EXPECT_FALSE(capped.Finished(99));
  EXPECT_TRUE(capped.Finished(100));

  RunClock both(100, 10, 0);
  both.AddStep(5.0, 10);
  EXPECT_DOUBLE_EQ(both.Progress(10), 0.5);
  both.AddStep(5.0, 10);
  EXPECT_TRUE(both.Finished(20));
}

TEST(RunClock, NoCapWithABudgetRunsOnTime) {
  RunClock clock(0, 10, 0);
  clock.AddStep(4.0, 10);
  EXPECT_DOUBLE_EQ(clock.Progress(1000000), 0.4);
  EXPECT_FALSE(clock.Finished(1000000));
  EXPECT_DOUBLE_EQ(clock.Eta(1000000), 6.0);
  clock.AddStep(6.0, 10);
  EXPECT_TRUE(clock.Finished(1000000));
}

TEST(RunClock, ARevisedBudgetMovesTheEndButNeverTheProgressBack) {
  RunClock clock(0, 10, 0);
  clock.AddStep(5.0, 10);
  EXPECT_DOUBLE_EQ(clock.Progress(1), 0.5);
  clock.SetBudget(20);  // more time found: the schedule holds where it was until time catches up
  EXPECT_DOUBLE_EQ(clock.Progress(1), 0.5);
  EXPECT_FALSE(clock.Finished(1));
  clock.AddStep(7.0, 10);
  EXPECT_DOUBLE_EQ(clock.Progress(2), 0.6);
  clock.SetBudget(12);  // less: ends now
  EXPECT_TRUE(clock.Finished(2));
  EXPECT_DOUBLE_EQ(clock.Progress(2), 1.0);
}

TEST(RunClock, AResumedRunCountsItsEarlierSeconds) {
  RunClock clock(0, 10, 8.0);
  EXPECT_DOUBLE_EQ(clock.Progress(0), 0.8);
  clock.AddStep(2.0, 100);
  EXPECT_TRUE(clock.Finished(1));
  EXPECT_DOUBLE_EQ(clock.SamplesPerSecond(), 50.0);
}

}  // namespace
}  // namespace endorecon::train
