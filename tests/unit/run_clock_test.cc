// The training clock: the share of the run done (iterations or budget, never backwards when the
// budget is revised), the end (cap 0: none), and the ETA.
#include "worker/engine/train/run_clock.h"

#include <gtest/gtest.h>

#include <vector>

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

// The curve's points spread over a log time axis: a 20 s run had 3 (0.03 s, 10 s, its end).
TEST(CurveTimes, PointsComeEvenlyOnALogAxisThenEveryInterval) {
  CurveTimes curve(10, -1);
  std::vector<double> taken;
  for (double now = 0.03; now <= 60; now += 0.01) {
    if (!curve.Due(now)) continue;
    taken.push_back(now);
    curve.Taken(now, 0.01);
  }
  ASSERT_GE(taken.size(), 10u);
  EXPECT_NEAR(taken[0], 0.03, 1e-9) << "at the first step";
  EXPECT_NEAR(taken[1], 0.03 + 1.25, 0.011) << "no closer than a eighth of the interval";
  int before_10s = 0;
  for (std::size_t i = 1; i < taken.size(); ++i) {
    const double gap = taken[i] - taken[i - 1];
    EXPECT_LE(gap, 10.011);
    if (taken[i - 1] >= 2.5 && taken[i - 1] < 20) {
      EXPECT_NEAR(gap, 0.5 * taken[i - 1], 0.011);
    }
    before_10s += taken[i] < 10;
  }
  EXPECT_GE(before_10s, 5);
  EXPECT_NEAR(taken.back() - taken[taken.size() - 2], 10, 0.011) << "every interval later on";
  // A point that costs much is taken at most a tenth of the time.
  CurveTimes costly(10, -1);
  costly.Taken(0.5, 0.4);
  EXPECT_FALSE(costly.Due(4.4));
  EXPECT_TRUE(costly.Due(4.5));
}

}  // namespace
}  // namespace endorecon::train
