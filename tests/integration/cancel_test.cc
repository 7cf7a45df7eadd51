// Cancelling: a queued job at once, a running job within seconds (its worker stops and takes the
// next job), a finished job not at all.
#include <gtest/gtest.h>

#include "tests/integration/service_harness.h"

namespace endorecon::testing {
namespace {

TEST(CancelTest, QueuedJobIsCancelledAtOnce) {
  Cluster cluster;
  MakeClip(cluster.path("clip"));
  const auto id = cluster.Submit(cluster.path("clip"), {"--iterations", "30"});
  const auto cancelled = RunCli(cluster.address(), {"cancel", id});
  EXPECT_EQ(cancelled.exit_code, 0) << cancelled.err;
  EXPECT_EQ(cluster.Job(id).state(), v1::CANCELLED);
  const auto again = RunCli(cluster.address(), {"cancel", id});
  EXPECT_EQ(again.exit_code, 7) << again.err;
  EXPECT_NE(again.err.find("already CANCELLED"), std::string::npos) << again.err;
  // No worker ever sees it.
  cluster.StartWorker("w1");
  const auto next = cluster.Submit(cluster.path("clip"), {"--iterations", "30"});
  EXPECT_EQ(cluster.WaitForState(next, v1::SUCCEEDED).state(), v1::SUCCEEDED);
  EXPECT_EQ(cluster.Job(id).state(), v1::CANCELLED);
}

TEST(CancelTest, RunningJobStopsWithinSecondsAndTheWorkerMovesOn) {
  Cluster cluster;
  MakeClip(cluster.path("clip"));
  auto& worker = cluster.StartWorker("w1");
  const auto id = cluster.Submit(cluster.path("clip"), {"--iterations", "100000"});
  ASSERT_TRUE(WaitUntil([&] { return cluster.Job(id).progress().iteration() > 0; })) << cluster.ServerLog();
  const auto cancelled = RunCli(cluster.address(), {"cancel", id});
  EXPECT_EQ(cancelled.exit_code, 0);
  EXPECT_NE(cancelled.out.find("cancel requested"), std::string::npos) << cancelled.out;
  const auto job = cluster.WaitForState(id, v1::CANCELLED, std::chrono::seconds(20));
  EXPECT_EQ(job.state(), v1::CANCELLED);
  EXPECT_NE(job.error().find("cancelled by request"), std::string::npos);
  EXPECT_EQ(RunCli(cluster.address(), {"watch", id}).exit_code, 6);
  const auto next = cluster.Submit(cluster.path("clip"), {"--iterations", "30"});
  EXPECT_EQ(cluster.WaitForState(next, v1::SUCCEEDED).state(), v1::SUCCEEDED) << worker.Log();
  EXPECT_NE(worker.Log().find("STOP_CANCELLED"), std::string::npos);
  const auto fetch = RunCli(cluster.address(), {"fetch", id, "-o", cluster.path("out").string()});
  EXPECT_EQ(fetch.exit_code, 7);
}

}  // namespace
}  // namespace endorecon::testing
