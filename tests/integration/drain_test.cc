// An admin drains a worker for maintenance: it is given no new job while its running one goes on,
// a server restart does not undo it, and `--undo` puts it back in service.
#include <gtest/gtest.h>

#include <chrono>
#include <csignal>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>

#include "tests/integration/audit_reader.h"
#include "tests/integration/service_harness.h"

namespace endorecon::testing {
namespace {

TEST(DrainTest, ADrainingWorkerIsGivenNoNewJobAndUndoPutsItBack) {
  Cluster cluster;
  auto& worker = cluster.StartWorker("w-maint");
  ASSERT_TRUE(WaitUntil([&] { return RunCli(cluster.address(), {"workers"}).out.find("w-maint") != std::string::npos; }))
      << worker.Log();
  const auto unknown = RunCli(cluster.address(), {"drain", "w-other"});
  EXPECT_EQ(unknown.exit_code, 3) << unknown.err;
  EXPECT_NE(unknown.err.find("no worker 'w-other' (known: w-maint"), std::string::npos) << unknown.err;

  const auto drained = RunCli(cluster.address(), {"drain", "w-maint"});
  ASSERT_EQ(drained.exit_code, 0) << drained.err;
  EXPECT_NE(drained.out.find("worker w-maint drains: it is given no new job and runs none"), std::string::npos)
      << drained.out;
  EXPECT_NE(RunCli(cluster.address(), {"workers"}).out.find("draining"), std::string::npos);
  MakeClip(cluster.path("clip"));
  const auto submitted =
      RunCli(cluster.address(), {"--json", "submit", cluster.path("clip").string(), "--iterations", "20"});
  ASSERT_EQ(submitted.exit_code, 0) << submitted.err;
  const auto id = submitted.out.substr(submitted.out.find("\"id\":\"") + 6, 12);
  std::this_thread::sleep_for(std::chrono::seconds(3));
  EXPECT_EQ(cluster.Job(id).state(), v1::QUEUED) << "the only worker drains";
  // Ctrl-C while watching ends the watch, not the job, and says how to follow it again.
  Process watch({BuiltBinary("client/endorecon"), "--server", cluster.address(), "watch", id},
                cluster.path("watch.log"));
  ASSERT_TRUE(WaitUntil([&] { return watch.Log().find("QUEUED") != std::string::npos; })) << watch.Log();
  watch.Signal(SIGINT);
  EXPECT_EQ(watch.Wait(), 130);
  EXPECT_NE(
      watch.Log().find("stopped watching; job " + id + " goes on on the server: `endorecon watch " + id),
      std::string::npos)
      << watch.Log();
  EXPECT_EQ(cluster.Job(id).state(), v1::QUEUED);
  // A server restart keeps the drain: the worker registers again (the same process) and still drains.
  cluster.KillServer(SIGKILL);
  cluster.StartServer();
  ASSERT_TRUE(WaitUntil([&] { return worker.Log().find("registered again") != std::string::npos; }))
      << worker.Log();
  std::this_thread::sleep_for(std::chrono::seconds(3));
  EXPECT_NE(RunCli(cluster.address(), {"workers"}).out.find("draining"), std::string::npos);
  EXPECT_EQ(cluster.Job(id).state(), v1::QUEUED) << "drained before the restart";

  const auto undone = RunCli(cluster.address(), {"drain", "w-maint", "--undo"});
  ASSERT_EQ(undone.exit_code, 0) << undone.err;
  EXPECT_NE(undone.out.find("serves again"), std::string::npos) << undone.out;
  // The audit log tells a drain from its undo (they read alike; found 2026-12-06).
  const auto audit = AuditLines(cluster.data_dir() / "audit.jsonl");
  EXPECT_EQ(AuditFind(audit, "Drain", "OK").size(), 1u);
  EXPECT_EQ(AuditFind(audit, "DrainUndo", "OK").size(), 1u);
  EXPECT_EQ(cluster.WaitForState(id, v1::SUCCEEDED).worker_id(), "w-maint");
  // The last event of a watch of a settled job carries its result manifest, for scripts.
  const auto watched = RunCli(cluster.address(), {"--json", "watch", id});
  ASSERT_EQ(watched.exit_code, 0) << watched.err;
  const auto last_line = watched.out.substr(watched.out.rfind('\n', watched.out.size() - 2) + 1);
  const auto last = nlohmann::json::parse(last_line);
  EXPECT_EQ(last["job"]["state"], "SUCCEEDED") << last_line;
  EXPECT_GT(last["job"]["result"]["files"].size(), 0u) << last_line;
  EXPECT_EQ(RunCli(cluster.address(), {"workers"}).out.find("draining"), std::string::npos);
}

}  // namespace
}  // namespace endorecon::testing
