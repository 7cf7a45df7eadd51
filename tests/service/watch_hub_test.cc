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

v1::Job JobIn(const std::string& id, v1::JobState state) {
  v1::Job job;
  job.set_id(id);
  job.set_state(state);
  return job;
}

TEST(WatchHubTest, SettledJobsAreDroppedAfterTheirGraceAndComeBackWithNewerVersions) {
  using std::chrono::seconds;
  WatchHub hub;
  const auto now = std::chrono::steady_clock::now();
  hub.PublishJob(JobIn("running", v1::RUNNING));
  auto sending = JobIn("sending", v1::SUCCEEDED);
  sending.add_sends()->set_state(v1::DicomSend::PENDING);
  hub.PublishJob(sending);
  hub.PublishJob(JobIn("done", v1::SUCCEEDED));
  hub.Wait("never-published", 0, Soon());  // a watcher's empty entry
  ASSERT_EQ(hub.Size(), 4u);

  EXPECT_EQ(hub.Prune(now, seconds(60)), 1u) << "only the empty entry goes at once";
  EXPECT_EQ(hub.Prune(now + seconds(120), seconds(60)), 1u) << "then the settled job, after its grace";
  EXPECT_EQ(hub.Size(), 2u) << "a running job and a job with a DICOM send waiting stay";

  // A watcher that saw the dropped entry still sees what is published for the job later (a send
  // requested again), though the entry is a new one.
  const auto seen = hub.Wait("sending", 0, Soon()).version;
  hub.Prune(now + seconds(120), seconds(60));
  auto resent = JobIn("done", v1::SUCCEEDED);
  resent.add_sends()->set_state(v1::DicomSend::PENDING);
  hub.PublishJob(resent);
  const auto changes = hub.Wait("done", seen, Soon());
  ASSERT_TRUE(changes.job.has_value());
  EXPECT_EQ(changes.job->sends_size(), 1);
}

TEST(WatchHubTest, AnEntryAWatcherIsWaitingOnIsNotDropped) {
  WatchHub hub;
  hub.PublishJob(JobIn("done", v1::CANCELLED));
  const auto seen = hub.Wait("done", 0, Soon()).version;
  std::thread watcher(
      [&] { hub.Wait("done", seen, std::chrono::steady_clock::now() + std::chrono::seconds(2)); });
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  EXPECT_EQ(hub.Prune(std::chrono::steady_clock::now() + std::chrono::hours(1), std::chrono::seconds(60)),
            0u);
  watcher.join();
  EXPECT_EQ(hub.Prune(std::chrono::steady_clock::now() + std::chrono::hours(1), std::chrono::seconds(60)),
            1u);
}

}  // namespace
}  // namespace endorecon::server
