// Workers go away mid-job: killed (the lease expires, the attempt counts, another worker resumes
// from the last checkpoint) or stopped with SIGTERM (the job is handed back cleanly, no attempt lost).
#include <gtest/gtest.h>
#include <signal.h>

#include <chrono>
#include <thread>

#include "tests/integration/service_harness.h"

namespace endorecon::testing {
namespace {

// Waits until the running job has reported progress and uploaded a checkpoint.
v1::Job WaitForCheckpoint(Cluster& cluster, const std::string& id) {
  v1::Job job;
  WaitUntil([&] {
    job = cluster.Job(id);
    return job.state() == v1::RUNNING && !job.checkpoint().sha256().empty() &&
           job.progress().iteration() >= 10;
  });
  return job;
}

TEST(WorkerLossTest, KilledWorkerJobCompletesElsewhereFromItsCheckpoint) {
  Cluster cluster;
  MakeClip(cluster.path("clip"));
  cluster.StartWorker("doomed", {"--checkpoint-interval", "0.5"});
  const auto id = cluster.Submit(cluster.path("clip"), {"--iterations", "200"});
  const auto before = WaitForCheckpoint(cluster, id);
  ASSERT_EQ(before.state(), v1::RUNNING) << cluster.ServerLog();
  ASSERT_EQ(before.worker_id(), "doomed");
  cluster.StopWorker("doomed", SIGKILL);

  auto& rescuer = cluster.StartWorker("rescuer");
  const auto done = cluster.WaitForState(id, v1::SUCCEEDED, std::chrono::seconds(120));
  ASSERT_EQ(done.state(), v1::SUCCEEDED) << done.error() << cluster.ServerLog() << rescuer.Log();
  EXPECT_EQ(done.worker_id(), "rescuer");
  EXPECT_EQ(done.attempts(), 1);  // the vanished worker's attempt counts
  EXPECT_NE(rescuer.Log().find("resuming from checkpoint"), std::string::npos) << rescuer.Log();
  EXPECT_NE(rescuer.Log().find("resumed from"), std::string::npos) << rescuer.Log();
  EXPECT_NE(cluster.ServerLog().find("its lease expired"), std::string::npos);
}

TEST(WorkerLossTest, JobFailsWithReasonAfterMaxAttempts) {
  Cluster cluster({"--max-attempts", "1"});
  MakeClip(cluster.path("clip"));
  cluster.StartWorker("doomed", {"--checkpoint-interval", "0.5"});
  const auto id = cluster.Submit(cluster.path("clip"), {"--iterations", "200"});
  WaitUntil([&] { return cluster.Job(id).progress().iteration() > 0; });
  cluster.StopWorker("doomed", SIGKILL);
  const auto failed = cluster.WaitForState(id, v1::FAILED);
  ASSERT_EQ(failed.state(), v1::FAILED) << cluster.ServerLog();
  EXPECT_NE(failed.error().find("gave up after 1 attempt"), std::string::npos) << failed.error();
  EXPECT_NE(failed.error().find("doomed"), std::string::npos) << failed.error();
  const auto status = RunCli(cluster.address(), {"watch", id});
  EXPECT_EQ(status.exit_code, 5);
}

TEST(WorkerLossTest, SigtermHandsTheJobBackWithoutLosingAnAttempt) {
  Cluster cluster;
  MakeClip(cluster.path("clip"));
  auto& leaving = cluster.StartWorker("leaving", {"--checkpoint-interval", "0.5"});
  const auto id = cluster.Submit(cluster.path("clip"), {"--iterations", "200"});
  WaitForCheckpoint(cluster, id);
  // Twice at once, as GNU timeout and a kill of the process group deliver it: one request to stop,
  // the job handed back (the second stopped the worker at once until 2026-12-07).
  leaving.Signal(SIGTERM);
  std::this_thread::sleep_for(std::chrono::milliseconds(50));  // taken apart, not merged by the kernel
  leaving.Signal(SIGTERM);
  EXPECT_EQ(leaving.Wait(), 0) << leaving.Log();
  const auto requeued = cluster.Job(id);
  EXPECT_EQ(requeued.state(), v1::QUEUED) << cluster.ServerLog();
  EXPECT_EQ(requeued.attempts(), 0);
  EXPECT_FALSE(requeued.checkpoint().sha256().empty());
  EXPECT_NE(requeued.error().find("shutting down"), std::string::npos) << requeued.error();

  cluster.StartWorker("next");
  const auto done = cluster.WaitForState(id, v1::SUCCEEDED, std::chrono::seconds(120));
  EXPECT_EQ(done.state(), v1::SUCCEEDED) << cluster.ServerLog();
  EXPECT_EQ(done.attempts(), 0);
}

}  // namespace
}  // namespace endorecon::testing
