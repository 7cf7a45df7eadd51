// A worker's run whose lease is gone before it can report (expired while the worker was stalled,
// or given to another worker): the run ends without an exception and leaves no job folder. The
// hand-back of such a run failed and threw out of the runner's error path, skipping the folder's
// removal, so a long-running worker kept each such job's clip and results on its disk (found by
// the fault campaign under TSan, where leases expire).
#include <gtest/gtest.h>

#include <atomic>
#include <filesystem>

#include "tests/integration/leased_worker.h"
#include "tests/integration/service_harness.h"
#include "worker/runtime/job_runner.h"

namespace endorecon::testing {
namespace {

TEST(LostLeaseTest, ARunWhoseLeaseIsGoneEndsQuietlyAndLeavesNoFolder) {
  Cluster cluster({"--max-attempts", "1"});
  MakeClip(cluster.path("clip"));
  const auto id = cluster.Submit(cluster.path("clip"), {"--iterations", "5"});

  auto [device, client, lease] = LeaseAsWorker(cluster, "stalled");
  ASSERT_TRUE(lease.has_value()) << cluster.ServerLog();
  ASSERT_EQ(lease->job().id(), id);
  // Nothing reports for the lease: it runs out and the job's only attempt is spent.
  ASSERT_EQ(cluster.WaitForState(id, v1::FAILED).state(), v1::FAILED) << cluster.ServerLog();

  worker::RunnerSettings settings;
  settings.work_dir = cluster.path("scratch");
  settings.min_free_bytes = 0;
  worker::WorkerMetrics metrics("", {device});
  const std::atomic<bool> shutting_down{false};
  EXPECT_NO_THROW(worker::RunLeasedJob(*client, *lease, device, settings, metrics, shutting_down));
  EXPECT_FALSE(std::filesystem::exists(settings.work_dir / id));
  EXPECT_EQ(cluster.Job(id).state(), v1::FAILED);
}

}  // namespace
}  // namespace endorecon::testing
