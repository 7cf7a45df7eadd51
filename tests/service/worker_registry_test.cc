#include "server/worker_registry.h"

#include <gtest/gtest.h>

#include <chrono>

#include "common/error.h"
#include "tests/unit/temp_dir.h"

namespace endorecon::server {
namespace {

// A worker's default id is host-pid: every restart added one to the registry for good, and
// `endorecon workers` listed them all (found by reading the code, 2026-12-05).
TEST(WorkerRegistryTest, WorkersGoneLongAndHoldingNoJobAreForgotten) {
  WorkerRegistry registry(std::chrono::seconds(30));
  for (const char* id : {"host-101", "host-102"}) {
    v1::RegisterRequest request;
    request.set_worker_id(id);
    request.add_devices("cpu0");
    registry.Register(request);
  }
  registry.AddJob("host-102", "job-1");
  const auto later = std::chrono::steady_clock::now() + std::chrono::hours(1);
  EXPECT_EQ(registry.Forget(std::chrono::steady_clock::now() - std::chrono::hours(1)), 0u);
  EXPECT_EQ(registry.Forget(later), 1u) << "the one holding a job stays";
  ASSERT_EQ(registry.List().size(), 1u);
  EXPECT_EQ(registry.List()[0].id(), "host-102");
  EXPECT_FALSE(registry.Registered("host-101"));
}

// A lease call of a worker that left, reaching the server after its Leave, listed the stopped worker
// alive (CI, 2026-12-07): after a Leave only a registration brings it back.
TEST(WorkerRegistryTest, AWorkerThatLeftStaysGoneUntilItRegistersAgain) {
  WorkerRegistry registry(std::chrono::seconds(30));
  v1::RegisterRequest request;
  request.set_worker_id("w1");
  request.add_devices("cpu0");
  registry.Register(request);
  ASSERT_TRUE(registry.List()[0].alive());
  registry.Leave("w1");
  registry.Touch("w1");  // the late lease call
  EXPECT_FALSE(registry.List()[0].alive());
  registry.Register(request);
  EXPECT_TRUE(registry.List()[0].alive());
}

// A drain lasts until undone or until the worker registers again (a restart after maintenance).
TEST(WorkerRegistryTest, ADrainLastsUntilUndoneOrTheWorkersNextRegistration) {
  WorkerRegistry registry(std::chrono::seconds(30));
  v1::RegisterRequest request;
  request.set_worker_id("gpu-7");
  request.add_devices("cuda:0");
  registry.Register(request);
  registry.AddJob("gpu-7", "job-1");
  const v1::WorkerInfo drained = registry.SetDraining("gpu-7", true);
  EXPECT_TRUE(drained.draining());
  ASSERT_EQ(drained.job_ids_size(), 1);
  EXPECT_TRUE(registry.Draining("gpu-7"));
  EXPECT_TRUE(registry.List()[0].draining());
  EXPECT_FALSE(registry.SetDraining("gpu-7", false).draining());
  registry.SetDraining("gpu-7", true);
  registry.Register(request);
  EXPECT_FALSE(registry.Draining("gpu-7"));
  EXPECT_FALSE(registry.Draining("unknown"));
  EXPECT_THROW(registry.SetDraining("unknown", true), Error);
}

// A drain outlives a server restart (a server upgraded in a maintenance window put every drained
// worker back in service until 2026-12-06): kept in the drains file, and kept by the registration a
// worker makes because the server restarted (`again`); a restarted worker's registration ends it.
TEST(WorkerRegistryTest, ADrainOutlivesAServerRestartButNotTheWorkersRestart) {
  testing::TempDir dir("drains");
  const auto file = dir / "drains.json";
  v1::RegisterRequest request;
  request.set_worker_id("gpu-7");
  {
    WorkerRegistry registry(std::chrono::seconds(30), file);
    registry.Register(request);
    registry.Register([] {
      v1::RegisterRequest other;
      other.set_worker_id("gpu-8");
      return other;
    }());
    registry.SetDraining("gpu-7", true);
  }
  WorkerRegistry restarted(std::chrono::seconds(30), file);
  EXPECT_TRUE(restarted.Draining("gpu-7"));
  EXPECT_FALSE(restarted.Draining("gpu-8"));
  ASSERT_EQ(restarted.List().size(), 1u) << "a drained worker is listed from the start";
  EXPECT_FALSE(restarted.List()[0].alive()) << "until it calls";
  EXPECT_FALSE(restarted.Registered("gpu-7")) << "so its lease asks it to register again";
  v1::RegisterRequest again = request;
  again.set_again(true);
  restarted.Register(again);
  EXPECT_TRUE(restarted.Draining("gpu-7"));
  EXPECT_TRUE(restarted.List()[0].alive());
  restarted.Register(request);  // the worker restarted
  EXPECT_FALSE(restarted.Draining("gpu-7"));
  EXPECT_FALSE(WorkerRegistry(std::chrono::seconds(30), file).Draining("gpu-7"));

  // A file that is not the registry's is warned of and left aside: the server still starts.
  testing::WriteBytes(file, R"({"draining": ["gpu-7"]})");
  EXPECT_FALSE(WorkerRegistry(std::chrono::seconds(30), file).Draining("gpu-7"));
}

// A live worker's calls that carry another token than it registered with are noted for the log:
// a rotated token, or a second worker claiming its id (which merged with the first in `workers` and
// undid its drain; found 2026-12-06). The server cannot tell which, and refuses neither: a refusal
// stopped a worker whose token was rotated.
TEST(WorkerRegistryTest, AWorkersChangeOfTokenIsNoted) {
  WorkerRegistry registry(std::chrono::seconds(30));
  v1::RegisterRequest request;
  request.set_worker_id("wk1");
  request.add_devices("cpu0");
  EXPECT_EQ(registry.Register(request, "node-3-token"), "");
  EXPECT_EQ(registry.NoteToken("wk1", "node-3-token"), "");
  EXPECT_EQ(registry.NoteToken("wk1", "node-3-rotated"), "node-3-token");
  EXPECT_EQ(registry.NoteToken("wk1", "node-3-rotated"), "") << "noted once";
  EXPECT_EQ(registry.Register(request, "node-9-token"), "node-3-rotated");
  // A token of another scope written into its --token-file: listed with the scope its calls carry.
  registry.NoteToken("wk1", "research-token", "research");
  EXPECT_EQ(registry.List()[0].tenant(), "research");
  registry.NoteToken("wk1", "node-9-token");
  EXPECT_EQ(registry.List()[0].tenant(), "");
  // A worker the server knows only from its calls (it restarted since the worker registered).
  registry.Touch("wk2");
  EXPECT_EQ(registry.NoteToken("wk2", "any"), "");
  request.set_worker_id("wk2");
  EXPECT_EQ(registry.Register(request, "node-3-token"), "");
  EXPECT_TRUE(registry.Registered("wk2"));
}

}  // namespace
}  // namespace endorecon::server
