// A real Prometheus (the Debian package) scrapes the server and a worker; the values read back
// through its HTTP API show the job that ran.
#include <gtest/gtest.h>

#include <fstream>

#include "tests/integration/service_harness.h"

namespace endorecon::testing {
namespace {

// The first sample value of an instant query, or -1 when there is none yet.
double Query(int prometheus_port, const std::string& expression) {
  const auto json = Capture("curl -s --max-time 5 'http://127.0.0.1:" + std::to_string(prometheus_port) +
                            "/api/v1/query' --data-urlencode 'query=" + expression + "'");
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
  ASSERT_TRUE(WaitUntil([&] { return cluster.worker_metrics_port("w1") > 0; }));
  const int prometheus_port = FreePort();
  const auto config = cluster.path("prometheus.yml");
  std::ofstream(config)
      << "global:\n  scrape_interval: 1s\n"
      << "scrape_configs:\n"
      << "  - job_name: endorecon-server\n    static_configs:\n      - targets: ['127.0.0.1:"
      << cluster.metrics_port() << "']\n"
      << "  - job_name: endorecon-worker\n    static_configs:\n      - targets: ['127.0.0.1:"
      << cluster.worker_metrics_port("w1") << "']\n";
  Process prometheus({"/usr/bin/prometheus", "--config.file=" + config.string(),
                      "--storage.tsdb.path=" + cluster.path("tsdb").string(),
                      "--web.listen-address=127.0.0.1:" + std::to_string(prometheus_port)},
                     cluster.path("prometheus.log"));
  ASSERT_TRUE(WaitUntil([&] { return Query(prometheus_port, "up") >= 0; })) << prometheus.Log();

  MakeClip(cluster.path("clip"));
  const auto result =
      RunCli(cluster.address(), {"submit", cluster.path("clip").string(), "--iterations", "30", "--wait"});
  ASSERT_EQ(result.exit_code, 0) << result.err;

  EXPECT_TRUE(WaitUntil([&] { return Query(prometheus_port, "endorecon_jobs_completed_total") == 1; }));
  EXPECT_TRUE(WaitUntil([&] { return Query(prometheus_port, "endorecon_jobs_submitted_total") == 1; }));
  EXPECT_TRUE(WaitUntil([&] { return Query(prometheus_port, "endorecon_jobs{state=\"SUCCEEDED\"}") == 1; }));
  EXPECT_TRUE(WaitUntil([&] { return Query(prometheus_port, "endorecon_upload_bytes_total") > 0; }));
  EXPECT_TRUE(WaitUntil([&] { return Query(prometheus_port, "endorecon_job_duration_seconds_count") == 1; }));
  EXPECT_TRUE(WaitUntil([&] { return Query(prometheus_port, "endorecon_workers_connected") == 1; }));
  EXPECT_TRUE(WaitUntil([&] { return Query(prometheus_port, "endorecon_worker_iterations_total") > 0; }));
  EXPECT_TRUE(WaitUntil([&] { return Query(prometheus_port, "endorecon_worker_memory_bytes") > 1e6; }));
  EXPECT_TRUE(WaitUntil([&] { return Query(prometheus_port, "endorecon_worker_samples_per_second") > 0; }));
  EXPECT_EQ(Query(prometheus_port, "endorecon_worker_device_info{device=\"cpu0\",kind=\"cpu\"}"), 1);
  EXPECT_EQ(Query(prometheus_port, "up{job=\"endorecon-worker\"}"), 1);
}

}  // namespace
}  // namespace endorecon::testing
