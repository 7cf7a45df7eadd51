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

// A worker whose token serves one tenant takes that tenant's jobs in their order and leaves the rest
// queued in theirs; one waiting is woken by its tenant's job even when another's came first.
TEST(SchedulerTest, AWorkerOfOneTenantTakesItsTenantsJobsAndLeavesTheRest) {
  Scheduler scheduler;
  scheduler.Push("a-old", 0, 1, "a");
  scheduler.Push("b", 5, 2, "b");
  scheduler.Push("a-high", 9, 3, "a");
  scheduler.Push("no-tenant", 0, 4);
  const auto now = [] { return std::chrono::steady_clock::now(); };
  EXPECT_EQ(scheduler.PopWait(now(), "b"), "b");
  EXPECT_EQ(scheduler.PopWait(now(), "b"), std::nullopt);
  EXPECT_EQ(scheduler.PopWait(now(), "a"), "a-high");
  EXPECT_EQ(scheduler.Depth(), 2u);
  EXPECT_EQ(PopNow(scheduler), "a-old") << "a worker of every tenant takes the queue's head";
  EXPECT_EQ(scheduler.PopWait(now(), ""), "no-tenant");

  std::optional<std::string> got;
  std::thread waiter([&] { got = scheduler.PopWait(now() + std::chrono::seconds(30), "c"); });
  scheduler.Push("b-late", 0, 5, "b");
  scheduler.Push("c-late", 0, 6, "c");
  waiter.join();
  EXPECT_EQ(got, "c-late");
  EXPECT_EQ(PopNow(scheduler), "b-late");
}

}  // namespace
}  // namespace endorecon::server
