// A real Prometheus (the Debian package) scrapes the server and a worker; the values read back
// through its HTTP API show the job that ran.
#include <gtest/gtest.h>

#include "tests/integration/prometheus_harness.h"

namespace endorecon::testing {
namespace {

// The first sample value of an instant query, or -1 when there is none yet.
double Query(const PrometheusScraper& prometheus, const std::string& expression) {
  const auto json = prometheus.Query(expression);
  const auto value = json.find("\"value\":[");
  if (value == std::string::npos) return -1;
  const auto quote = json.find(",\"", value);
  return std::stod(json.substr(quote + 2));
}

TEST(PrometheusScrapeTest, ServerAndWorkerMetricsReachPrometheus) {
  if (!std::filesystem::exists("/usr/bin/prometheus"))
    GTEST_SKIP() << "prometheus is not installed (scripts/install-deps)";
  Cluster cluster;
  cluster.StartWorker("w1");
  const PrometheusScraper prometheus(cluster, "w1");

  MakeClip(cluster.path("clip"));
  const auto result =
      RunCli(cluster.address(), {"submit", cluster.path("clip").string(), "--iterations", "30", "--wait"});
  ASSERT_EQ(result.exit_code, 0) << result.err;

  EXPECT_TRUE(WaitUntil([&] { return Query(prometheus, "endorecon_jobs_completed_total") == 1; }));
  EXPECT_TRUE(WaitUntil([&] { return Query(prometheus, "endorecon_jobs_submitted_total") == 1; }));
  EXPECT_TRUE(WaitUntil([&] { return Query(prometheus, "endorecon_jobs{state=\"SUCCEEDED\"}") == 1; }));
  EXPECT_TRUE(WaitUntil([&] { return Query(prometheus, "endorecon_upload_bytes_total") > 0; }));
  EXPECT_TRUE(WaitUntil([&] { return Query(prometheus, "endorecon_job_duration_seconds_count") == 1; }));
  EXPECT_TRUE(WaitUntil([&] { return Query(prometheus, "endorecon_workers_connected") == 1; }));
  EXPECT_TRUE(WaitUntil([&] { return Query(prometheus, "endorecon_worker_iterations_total") > 0; }));
  EXPECT_TRUE(WaitUntil([&] { return Query(prometheus, "endorecon_worker_memory_bytes") > 1e6; }));
  EXPECT_TRUE(WaitUntil([&] { return Query(prometheus, "endorecon_worker_samples_per_second") > 0; }));
  EXPECT_EQ(Query(prometheus, "endorecon_worker_device_info{device=\"cpu0\",kind=\"cpu\"}"), 1);
  EXPECT_EQ(Query(prometheus, "up{job=\"endorecon-worker\"}"), 1);
}

}  // namespace
}  // namespace endorecon::testing
