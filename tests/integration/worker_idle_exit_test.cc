// --exit-when-idle, for batch allocations (Slurm): a worker with nothing to do leaves instead of
// holding its allocation to the time limit, never while it runs a job, and its exit status tells
// an empty queue (0) from a server it could not reach or that refused it (69).
#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <string>

#include "tests/integration/service_harness.h"

namespace endorecon::testing {
namespace {

TEST(WorkerIdleExitTest, AWorkerLeavesWhenIdleButNotWhileItRunsAJob) {
  Cluster cluster;
  MakeClip(cluster.path("clip"));
  const auto id = cluster.Submit(cluster.path("clip"), {"--time-budget", "10"});
  const auto started = std::chrono::steady_clock::now();
  const auto target = cluster.path("targets") / "w-batch.json";
  // The default --lease-wait (10 s) is no longer than the idle time left: it left at the poll's end.
  auto& worker =
      cluster.StartWorker("w-batch", {"--exit-when-idle", "2", "--prometheus-target-file", target.string()});
  // While it serves, a Prometheus reading the folder finds it (file_sd_configs); gone when it leaves.
  ASSERT_TRUE(WaitUntil([&] { return std::filesystem::exists(target); })) << worker.Log();
  EXPECT_NE(ReadBytes(target).find("\"endorecon_worker\":\"w-batch\""), std::string::npos)
      << ReadBytes(target);
  EXPECT_EQ(worker.Wait(), 0) << worker.Log();
  const auto left_unix_ms = std::chrono::duration_cast<std::chrono::milliseconds>(
                                std::chrono::system_clock::now().time_since_epoch())
                                .count();
  EXPECT_FALSE(std::filesystem::exists(target));
  const auto job = cluster.Job(id);
  EXPECT_EQ(job.state(), v1::SUCCEEDED) << worker.Log();
  EXPECT_LT(left_unix_ms - job.finished_unix_ms(), 8000) << "2 s after its job, not at the poll's end";
  const auto ended = std::chrono::steady_clock::now();
  EXPECT_GE(ended - started, std::chrono::seconds(9)) << "left before its job ended";
  EXPECT_NE(worker.Log().find("no job for 2 s (--exit-when-idle): stopping"), std::string::npos)
      << worker.Log();
}

TEST(WorkerIdleExitTest, AWorkerThatCannotReachTheServerLeavesWithStatus69) {
  TempDir dir("idle");
  const int port = FreePort();  // nothing listens there
  Process worker({BuiltBinary("worker/runtime/endorecon-worker"), "serve", "--server",
                  "127.0.0.1:" + std::to_string(port), "--exit-when-idle", "2", "--metrics-port", "-1",
                  "--work-dir", (dir / "scratch").string()},
                 dir / "worker.log");
  EXPECT_EQ(worker.Wait(), 69) << worker.Log();
  EXPECT_NE(worker.Log().find("cannot register with 127.0.0.1:" + std::to_string(port) + " after 2 s"),
            std::string::npos)
      << worker.Log();
}

// Registered, then the server goes away for good: the worker leaves with 69 too.
TEST(WorkerIdleExitTest, AWorkerWhoseServerGoesAwayLeavesWithStatus69) {
  Cluster cluster;
  auto& worker = cluster.StartWorker("w-lost", {"--exit-when-idle", "3", "--lease-wait", "0.5"});
  ASSERT_TRUE(WaitUntil([&] { return worker.Log().find("serving") != std::string::npos; })) << worker.Log();
  cluster.KillServer(SIGKILL);
  EXPECT_EQ(worker.Wait(), 69) << worker.Log();
  EXPECT_NE(worker.Log().find("the server cannot be reached or refuses this worker (--exit-when-idle)"),
            std::string::npos)
      << worker.Log();
}

}  // namespace
}  // namespace endorecon::testing
