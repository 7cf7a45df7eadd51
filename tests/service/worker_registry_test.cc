#include "server/worker_registry.h"

#include <gtest/gtest.h>

#include <chrono>

#include "common/error.h"
#include "tests/unit/clip_fixture.h"

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

// A live worker's id is its token's: another token's worker claiming it merged with it in `workers`,
// undid its drain and could make it leave (found 2026-12-06). Its own token may register it again (a
// restart), and once it is gone another may take the id.
TEST(WorkerRegistryTest, ALiveWorkersIdBelongsToItsToken) {
  WorkerRegistry registry(std::chrono::milliseconds(200));
  v1::RegisterRequest request;
  request.set_worker_id("wk1");
  request.set_hostname("node-3");
  request.add_devices("cpu0");
  registry.Register(request, "node-3-token");
  registry.SetDraining("wk1", true);
  const std::string claimed =
      testing::ErrorFrom([&] { registry.Register(request, "node-9-token"); }, ErrorCode::kFailedPrecondition);
  EXPECT_NE(claimed.find("worker id 'wk1' is in use by a worker of token 'node-3-token' on node-3"),
            std::string::npos)
      << claimed;
  EXPECT_TRUE(registry.Draining("wk1"));
  EXPECT_NE(testing::ErrorFrom([&] { registry.Leave("wk1", "node-9-token"); }, ErrorCode::kPermissionDenied)
                .find("registered with another token"),
            std::string::npos);
  // Nor may it lease as that worker: the job's records would name it.
  EXPECT_NE(
      testing::ErrorFrom([&] { registry.CheckHolder("wk1", "node-9-token"); }, ErrorCode::kPermissionDenied)
          .find("worker 'wk1' registered with another token"),
      std::string::npos);
  registry.CheckHolder("wk1", "node-3-token");
  registry.CheckHolder("unknown", "node-9-token");
  EXPECT_TRUE(registry.List()[0].alive());
  registry.Register(request, "node-3-token");
  registry.Leave("wk1", "node-3-token");
  EXPECT_FALSE(registry.List()[0].alive());
  registry.Register(request, "node-9-token");  // gone: the id is free
  // A worker the server knows only from its calls (it restarted since the worker registered) takes
  // its id back by registering, whatever its token.
  registry.Touch("wk2");
  request.set_worker_id("wk2");
  registry.Register(request, "node-3-token");
  EXPECT_TRUE(registry.Registered("wk2"));
}

}  // namespace
}  // namespace endorecon::server
