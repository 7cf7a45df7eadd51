#include "server/watch_hub.h"

#include <gtest/gtest.h>

#include <thread>

namespace endorecon::server {
namespace {

auto Soon() { return std::chrono::steady_clock::now() + std::chrono::milliseconds(50); }

TEST(WatchHubTest, WatcherSeesOnlyWhatChangedSinceItLooked) {
  WatchHub hub;
  v1::Job job;
  job.set_id("j");
  job.set_state(v1::RUNNING);
  hub.PublishJob(job);
  v1::Progress progress;
  progress.set_iteration(10);
  hub.PublishProgress("j", progress);
  auto first = hub.Wait("j", 0, Soon());
  ASSERT_TRUE(first.job.has_value());
  ASSERT_TRUE(first.progress.has_value());
  progress.set_iteration(20);
  hub.PublishProgress("j", progress);
  progress.set_iteration(30);
  hub.PublishProgress("j", progress);
  auto second = hub.Wait("j", first.version, Soon());
  EXPECT_FALSE(second.job.has_value());
  ASSERT_TRUE(second.progress.has_value());
  EXPECT_EQ(second.progress->iteration(), 30);  // a slow watcher skips stale progress
  const auto none = hub.Wait("j", second.version, Soon());
  EXPECT_EQ(none.version, second.version);
  EXPECT_FALSE(none.progress.has_value());
}

TEST(WatchHubTest, TerminalJobDropsPreviewsAndWakesWaiters) {
  WatchHub hub;
  v1::Preview preview;
  preview.set_kind("uncertainty");
  hub.PublishPreview("j", preview);
  EXPECT_EQ(hub.Wait("j", 0, Soon()).previews.size(), 1u);
  WatchHub::Changes changes;
  std::thread waiter(
      [&] { changes = hub.Wait("j", 1, std::chrono::steady_clock::now() + std::chrono::seconds(30)); });
  v1::Job job;
  job.set_id("j");
  job.set_state(v1::SUCCEEDED);
  hub.PublishJob(job);
  waiter.join();
  ASSERT_TRUE(changes.job.has_value());
  EXPECT_EQ(changes.job->state(), v1::SUCCEEDED);
  EXPECT_TRUE(hub.Wait("j", 0, Soon()).previews.empty());
}

}  // namespace
}  // namespace endorecon::server
