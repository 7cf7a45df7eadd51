#include "server/scheduler.h"

#include <gtest/gtest.h>

#include <thread>

namespace endorecon::server {
namespace {

std::optional<std::string> PopNow(Scheduler& scheduler) {
  return scheduler.PopWait(std::chrono::steady_clock::now());
}

TEST(SchedulerTest, HigherPriorityFirstThenOldest) {
  Scheduler scheduler;
  scheduler.Push("old-low", 0, 1);
  scheduler.Push("new-high", 5, 4);
  scheduler.Push("old-high", 5, 2);
  scheduler.Push("new-low", 0, 3);
  EXPECT_EQ(scheduler.Depth(), 4u);
  EXPECT_EQ(PopNow(scheduler), "old-high");
  EXPECT_EQ(PopNow(scheduler), "new-high");
  EXPECT_EQ(PopNow(scheduler), "old-low");
  EXPECT_EQ(PopNow(scheduler), "new-low");
  EXPECT_EQ(PopNow(scheduler), std::nullopt);
}

TEST(SchedulerTest, RequeuedJobKeepsItsAgeAndIsNotDuplicated) {
  Scheduler scheduler;
  scheduler.Push("a", 0, 10);
  scheduler.Push("b", 0, 11);
  scheduler.Push("a", 0, 10);
  EXPECT_EQ(scheduler.Depth(), 2u);
  EXPECT_TRUE(scheduler.Remove("b"));
  EXPECT_FALSE(scheduler.Remove("b"));
  EXPECT_EQ(PopNow(scheduler), "a");
  EXPECT_EQ(scheduler.Depth(), 0u);
}

TEST(SchedulerTest, WaitingPopReceivesALaterPush) {
  Scheduler scheduler;
  std::optional<std::string> got;
  std::thread waiter(
      [&] { got = scheduler.PopWait(std::chrono::steady_clock::now() + std::chrono::seconds(30)); });
  scheduler.Push("late", 0, 1);
  waiter.join();
  EXPECT_EQ(got, "late");
}

TEST(SchedulerTest, ShutdownReleasesWaiters) {
  Scheduler scheduler;
  std::optional<std::string> got = "unset";
  std::thread waiter(
      [&] { got = scheduler.PopWait(std::chrono::steady_clock::now() + std::chrono::hours(1)); });
  scheduler.Shutdown();
  waiter.join();
  EXPECT_EQ(got, std::nullopt);
}

}  // namespace
}  // namespace endorecon::server
