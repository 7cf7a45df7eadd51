// Many clients at once: concurrent uploads (some of the same content), submissions, watchers and
// listings against one server and two workers; every job completes and every watcher sees it.
#include <gtest/gtest.h>

#include <atomic>
#include <thread>

#include "tests/integration/service_harness.h"

namespace endorecon::testing {
namespace {

TEST(ManyClientsTest, ConcurrentUploadsSubmissionsAndWatchers) {
  Cluster cluster;
  cluster.StartWorker("w1");
  cluster.StartWorker("w2");
  constexpr int kClients = 6;
  // Two distinct clips, each submitted by three clients at the same moment.
  MakeClip(cluster.path("clip0"), 1);
  MakeClip(cluster.path("clip1"), 2);
  std::vector<std::thread> clients;
  std::vector<CliResult> results(kClients);
  for (int i = 0; i < kClients; ++i) {
    clients.emplace_back([&, i] {
      results[i] =
          RunCli(cluster.address(), {"submit", cluster.path("clip" + std::to_string(i % 2)).string(),
                                     "--iterations", "10", "--wait", "--name", "client" + std::to_string(i)});
    });
  }
  std::atomic<int> listings_ok{0};
  std::vector<std::thread> listers;
  for (int i = 0; i < 4; ++i) {
    listers.emplace_back([&] {
      for (int k = 0; k < 5; ++k)
        listings_ok += RunCli(cluster.address(), {"--json", "list"}).exit_code == 0 ? 1 : 0;
    });
  }
  for (auto& client : clients) client.join();
  for (auto& lister : listers) lister.join();
  for (int i = 0; i < kClients; ++i) {
    EXPECT_EQ(results[i].exit_code, 0) << "client " << i << ": " << results[i].err << results[i].out;
    EXPECT_NE(results[i].out.find("SUCCEEDED"), std::string::npos) << results[i].out;
  }
  EXPECT_EQ(listings_ok, 20);
  const auto listed = RunCli(cluster.address(), {"list", "--state", "SUCCEEDED"});
  for (int i = 0; i < kClients; ++i)
    EXPECT_NE(listed.out.find("client" + std::to_string(i)), std::string::npos);
  const auto workers = RunCli(cluster.address(), {"workers"});
  EXPECT_NE(workers.out.find("w1"), std::string::npos);
  EXPECT_NE(workers.out.find("w2"), std::string::npos);
  // Each worker's devices with their kind, model, memory and threads.
  EXPECT_NE(workers.out.find("  cpu0: cpu, "), std::string::npos) << workers.out;
  EXPECT_NE(workers.out.find("host thread(s)"), std::string::npos) << workers.out;
  // ... and the build each runs, the CLI's own here.
  EXPECT_NE(workers.out.find("  version " + Capture(BuiltBinary("client/endorecon") + " --version")),
            std::string::npos)
      << workers.out;
}

}  // namespace
}  // namespace endorecon::testing
