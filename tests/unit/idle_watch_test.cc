#include "worker/runtime/idle_watch.h"

#include <gtest/gtest.h>

namespace endorecon::worker {
namespace {

using std::chrono::seconds;

// Idle is counted from the start and from the end of the last job on any device, never while one
// runs; the exit says whether the server was failing when the worker left.
TEST(IdleWatchTest, IdleCountsFromTheLastJobsEndAndNeverWhileOneRuns) {
  const auto t0 = IdleWatch::Clock::now();
  IdleWatch idle(seconds(60), t0);
  EXPECT_FALSE(idle.Due(t0 + seconds(59)));
  EXPECT_TRUE(idle.Due(t0 + seconds(60)));
  idle.JobStarted();
  idle.JobStarted();  // two devices
  EXPECT_FALSE(idle.Due(t0 + seconds(600)));
  idle.JobEnded(t0 + seconds(600));
  EXPECT_FALSE(idle.Due(t0 + seconds(700))) << "the other device still runs its job";
  idle.JobEnded(t0 + seconds(700));
  EXPECT_FALSE(idle.Due(t0 + seconds(759)));
  EXPECT_TRUE(idle.Due(t0 + seconds(760)));
  EXPECT_EQ(idle.ExitCode(), 0) << "not left yet";
  idle.ServerAnswered(false);
  idle.Leave();
  EXPECT_EQ(idle.ExitCode(), kIdleUnreachableExit);
  idle.ServerAnswered(true);
  EXPECT_EQ(idle.ExitCode(), 0) << "the queue was empty: a worker that had nothing to do";
}

// A lease's long poll waits no longer than the idle time left, so the worker leaves on time.
TEST(IdleWatchTest, WhatIsLeftBoundsTheLongPoll) {
  using std::chrono::milliseconds;
  const auto t0 = IdleWatch::Clock::now();
  IdleWatch idle(seconds(3), t0);
  EXPECT_EQ(idle.Left(t0 + seconds(1), milliseconds(10'000)), milliseconds(2000));
  EXPECT_EQ(idle.Left(t0 + seconds(5), milliseconds(10'000)), milliseconds(0));
  EXPECT_EQ(idle.Left(t0, milliseconds(500)), milliseconds(500));
  idle.JobStarted();
  EXPECT_EQ(idle.Left(t0 + seconds(5), milliseconds(10'000)), milliseconds(10'000)) << "a job runs";
  EXPECT_EQ(IdleWatch(seconds(0), t0).Left(t0, milliseconds(10'000)), milliseconds(10'000));
}

// Idle with no room in the scratch folder to take a job is no empty queue: the exit says so (it was
// 0, "the server had nothing", with a job waiting; found 2026-12-07), and room again clears it.
TEST(IdleWatchTest, LeavingWhileTheScratchFolderIsFullSaysSo) {
  const auto t0 = IdleWatch::Clock::now();
  IdleWatch idle(seconds(5), t0);
  idle.ServerAnswered(true);
  idle.ScratchFull(true);
  ASSERT_TRUE(idle.Due(t0 + seconds(5)));
  EXPECT_EQ(idle.ExitCode(), 0) << "not left yet";
  idle.Leave();
  EXPECT_EQ(idle.ExitCode(), kIdleScratchFullExit);
  idle.ScratchFull(false);
  EXPECT_EQ(idle.ExitCode(), 0);
}

TEST(IdleWatchTest, ALimitOfZeroIsNeverDue) {
  const auto t0 = IdleWatch::Clock::now();
  const IdleWatch idle(seconds(0), t0);
  EXPECT_FALSE(idle.Due(t0 + std::chrono::hours(10'000)));
}

}  // namespace
}  // namespace endorecon::worker
