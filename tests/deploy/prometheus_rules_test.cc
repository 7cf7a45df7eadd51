// The alert rules and the Grafana dashboard: promtool accepts the rules and their unit tests, and
// every metric they use is one a live server or worker exports.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <regex>
#include <set>
#include <string>

#include "tests/deploy/deploy_files.h"

namespace endorecon::testing {
namespace {

TEST(PrometheusRulesTest, PromtoolAcceptsTheRulesAndTheirTests) {
  if (!std::filesystem::exists("/usr/bin/promtool"))
    GTEST_SKIP() << "promtool is not installed (scripts/install-deps installs prometheus)";
  const auto dir = SourcePath("deploy/prometheus");
  const auto check = Capture("cd '" + dir.string() + "' && promtool check rules alerts.yml 2>&1; echo rc=$?");
  EXPECT_NE(check.find("SUCCESS: 13 rules found"), std::string::npos) << check;
  EXPECT_NE(check.find("rc=0"), std::string::npos) << check;
  const auto config =
      Capture("cd '" + dir.string() + "' && promtool check config prometheus.yml 2>&1; echo rc=$?");
  EXPECT_NE(config.find("rc=0"), std::string::npos) << config;
  const auto tests =
      Capture("cd '" + dir.string() + "' && promtool test rules alerts_test.yml 2>&1; echo rc=$?");
  EXPECT_NE(tests.find("SUCCESS"), std::string::npos) << tests;
  EXPECT_NE(tests.find("rc=0"), std::string::npos) << tests;
  for (const std::string alert :
       {"EndoreconQueueStuck", "EndoreconNoLiveWorkers", "EndoreconJobsFailing", "EndoreconDiskNearlyFull",
        "EndoreconLeaseExpiriesRising", "EndoreconWorkerTokenExpiring", "EndoreconStoredFilesDamaged"}) {
    EXPECT_NE(ReadBytes(dir / "alerts_test.yml").find("alertname: " + alert), std::string::npos)
        << alert << " has no unit test";
  }
}

// Every query of the dashboard is PromQL promtool parses (with its variables as "All" gives them),
// and keeps to the instances its Server or Workers variable picks: with two servers or many workers
// scraped, the panels summed them all (the dashboard had no variables until 2026-12-06).
TEST(PrometheusRulesTest, TheDashboardsQueriesParseAndKeepToThePickedInstances) {
  if (!std::filesystem::exists("/usr/bin/promtool"))
    GTEST_SKIP() << "promtool is not installed (scripts/install-deps installs prometheus)";
  const auto dashboard = nlohmann::json::parse(ReadBytes(SourcePath("deploy/grafana/endorecon.json")));
  std::set<std::string> variables;
  for (const auto& variable : dashboard.at("templating").at("list")) {
    variables.insert(variable.at("name").get<std::string>());
    EXPECT_EQ(variable.at("allValue"), ".*");
  }
  EXPECT_EQ(variables, (std::set<std::string>{"server", "worker"}));
  TempDir dir("dashboard-rules");
  std::string rules = "groups:\n  - name: dashboard\n    rules:\n";
  int count = 0;
  const std::regex metric("(endorecon_[a-z_]+)(\\{[^}]*\\})?");
  for (const auto& panel : dashboard.at("panels")) {
    for (const auto& target : panel.at("targets")) {
      const std::string expr = target.at("expr").get<std::string>();
      for (auto it = std::sregex_iterator(expr.begin(), expr.end(), metric); it != std::sregex_iterator();
           ++it) {
        const std::string scope = (*it)[1].str().starts_with("endorecon_worker_") ? "$worker" : "$server";
        EXPECT_NE((*it)[2].str().find("instance=~\"" + scope + "\""), std::string::npos)
            << panel.at("title") << ": " << (*it)[0].str() << " is not kept to " << scope;
      }
      std::string query = std::regex_replace(expr, std::regex("\\$(server|worker)"), ".*");
      rules += "      - record: dashboard:query_" + std::to_string(++count) +
               "\n        expr: " + nlohmann::json(query).dump() + "\n";
    }
  }
  WriteBytes(dir / "dashboard.yml", rules);
  const auto check =
      Capture("promtool check rules '" + (dir / "dashboard.yml").string() + "' 2>&1; echo rc=$?");
  EXPECT_NE(check.find("SUCCESS: " + std::to_string(count) + " rules found"), std::string::npos) << check;
  EXPECT_NE(check.find("rc=0"), std::string::npos) << check;
}

TEST(PrometheusRulesTest, AlertsAndDashboardUseOnlyExportedMetrics) {
  const auto every_series = ClusterOfEverySeries();
  Cluster& cluster = *every_series;
  const auto metrics_of = [](int port) {
    return Capture("curl -s --max-time 5 http://127.0.0.1:" + std::to_string(port) + "/metrics");
  };
  std::string exported;
  ASSERT_TRUE(WaitUntil([&] {
    const int worker_port = cluster.worker_metrics_port("w1");
    if (worker_port == 0) return false;
    exported = metrics_of(cluster.metrics_port()) + metrics_of(worker_port);
    return exported.find("endorecon_worker_busy") != std::string::npos;
  }));
  const auto available = MetricNames(exported);

  const auto dashboard = nlohmann::json::parse(ReadBytes(SourcePath("deploy/grafana/endorecon.json")));
  std::string expressions;
  ASSERT_FALSE(dashboard.at("panels").empty());
  for (const auto& panel : dashboard.at("panels")) {
    ASSERT_FALSE(panel.at("targets").empty()) << panel.at("title");
    for (const auto& target : panel.at("targets")) expressions += target.at("expr").get<std::string>() + "\n";
  }
  const auto used_by_dashboard = MetricNames(expressions);
  const auto used_by_alerts = MetricNames(ReadBytes(SourcePath("deploy/prometheus/alerts.yml")));
  // A worker with a GPU alone exports the GPU gauges: those are taken from what the worker
  // registers (worker_metrics.cc), this worker having none.
  std::set<std::string> gpu_only;
  for (const auto& name : MetricNames(ReadBytes(SourcePath("worker/runtime/worker_metrics.cc")))) {
    if (name.starts_with("endorecon_worker_gpu_")) gpu_only.insert(name);
  }
  EXPECT_EQ(gpu_only.size(), 3u);
  for (const auto& names : {used_by_dashboard, used_by_alerts}) {
    for (const auto& name : names)
      EXPECT_TRUE(available.count(name) || gpu_only.count(name)) << name << " is not exported";
  }
  for (const auto& name : gpu_only)
    EXPECT_TRUE(used_by_dashboard.count(name)) << name << " is not on the dashboard";
  // The dashboard shows every server metric.
  for (const auto& name : MetricNames(metrics_of(cluster.metrics_port()))) {
    const bool histogram_part =
        name.size() > 7 && (name.ends_with("_bucket") || name.ends_with("_count") || name.ends_with("_sum"));
    if (!histogram_part) {
      EXPECT_TRUE(used_by_dashboard.count(name) || used_by_dashboard.count(name + "_bucket"))
          << name << " is not on the dashboard";
    }
  }
}

}  // namespace
}  // namespace endorecon::testing
