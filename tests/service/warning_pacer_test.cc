#include "common/warning_pacer.h"

#include <gtest/gtest.h>

#include <thread>

namespace endorecon {
namespace {

TEST(WarningPacerTest, TheFirstIsSaidThenOnePerPeriodCountingWhatWasHeldBack) {
  WarningPacer hourly(std::chrono::hours(1));
  int held = -1;
  EXPECT_TRUE(hourly.Due(held));
  EXPECT_EQ(held, 0);
  for (int i = 0; i < 5; ++i) EXPECT_FALSE(hourly.Due(held));

  WarningPacer brief(std::chrono::milliseconds(20));
  EXPECT_TRUE(brief.Due(held));
  EXPECT_FALSE(brief.Due(held));
  EXPECT_FALSE(brief.Due(held));
  std::this_thread::sleep_for(std::chrono::milliseconds(40));
  EXPECT_TRUE(brief.Due(held));
  EXPECT_EQ(held, 2) << "the two held back are counted in the next line";
}

// The repeats of a burst's end were never said when no later repeat came to carry their count (found
// 2026-12-07): once the period is over, Overdue hands them over, once.
TEST(WarningPacerTest, RepeatsHeldBackAreOverdueOnceThePeriodEnds) {
  WarningPacer brief(std::chrono::milliseconds(20));
  int held = -1;
  EXPECT_FALSE(brief.Overdue(held)) << "nothing held";
  EXPECT_TRUE(brief.Due(held));
  EXPECT_FALSE(brief.Due(held));
  EXPECT_FALSE(brief.Due(held));
  EXPECT_FALSE(brief.Overdue(held)) << "the period is not over";
  std::this_thread::sleep_for(std::chrono::milliseconds(40));
  EXPECT_TRUE(brief.Overdue(held));
  EXPECT_EQ(held, 2);
  EXPECT_FALSE(brief.Overdue(held)) << "said once";
}

}  // namespace
}  // namespace endorecon
