// The Grafana dashboard as its reader meets it: a real Prometheus (the Debian package) scrapes a
// server and a worker that ran a job, and every panel's query, its variables as "All" gives them,
// returns a number. The query text alone (prometheus_rules_test.cc) passes a panel that filters on
// a label no series has, or that rates a series first made by the event it counts.
#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <regex>
#include <set>
#include <string>
#include <thread>

#include "tests/deploy/deploy_files.h"
#include "tests/integration/prometheus_harness.h"

namespace endorecon::testing {
namespace {

// The result of an instant query (its "data.result": one entry per series); null when Prometheus
// did not answer or refused the query.
nlohmann::json Query(const PrometheusScraper& prometheus, const std::string& expression) {
  const auto json = nlohmann::json::parse(prometheus.Query(expression), nullptr, false);
  if (json.is_discarded() || json.value("status", "") != "success") return nullptr;
  return json.at("data").at("result");
}

// Whether some series of `result` holds a number: histogram_quantile over no new observations gives
// NaN (a call made once shows no rate), which Grafana draws as nothing.
bool ShowsANumber(const nlohmann::json& result) {
  if (result.is_null()) return false;
  for (const auto& series : result) {
    if (!std::isnan(std::stod(series.at("value").at(1).get<std::string>()))) return true;
  }
  return false;
}

TEST(GrafanaDashboardTest, EveryPanelShowsNumbersFromARealPrometheus) {
  if (!std::filesystem::exists("/usr/bin/prometheus"))
    GTEST_SKIP() << "prometheus is not installed (scripts/install-deps installs it)";
  const auto every_series = ClusterOfEverySeries();
  Cluster& cluster = *every_series;
  const PrometheusScraper prometheus(cluster, "w1");

  // Scraped before the job, so that what it moves is an increase Prometheus sees.
  std::this_thread::sleep_for(std::chrono::seconds(3));
  MakeClip(cluster.path("clip"));
  const auto id = cluster.Submit(cluster.path("clip"), {"--iterations", "30"});
  ASSERT_EQ(cluster.WaitForState(id, v1::SUCCEEDED).state(), v1::SUCCEEDED) << cluster.ServerLog();
  auto fetch = MakeCredentials(cluster, "", "admin", "", "reader").CliFlags();
  fetch.insert(fetch.end(), {"fetch", id, "-o", cluster.path("result").string()});
  const auto fetched = RunCli(cluster.address(), fetch);
  ASSERT_EQ(fetched.exit_code, 0) << fetched.err;
  // A call with no token: refused, counted by its code.
  const auto refused = RunCli(cluster.address(), {"list"});
  EXPECT_NE(refused.exit_code, 0);

  // Only a worker with a GPU exports these (the test's worker has none).
  const std::set<std::string> gpu_panels{"Worker GPUs: utilisation (GPU workers only)",
                                         "Worker GPUs: memory in use of total (GPU workers only)"};
  const auto dashboard = nlohmann::json::parse(ReadBytes(SourcePath("deploy/grafana/endorecon.json")));
  std::set<std::string> shown_gpu_panels;
  for (const auto& panel : dashboard.at("panels")) {
    const auto title = panel.at("title").get<std::string>();
    if (gpu_panels.count(title)) {
      shown_gpu_panels.insert(title);
      continue;
    }
    for (const auto& target : panel.at("targets")) {
      const auto query =
          std::regex_replace(target.at("expr").get<std::string>(), std::regex("\\$(server|worker)"), ".*");
      nlohmann::json result;
      EXPECT_TRUE(WaitUntil(
          [&] {
            result = Query(prometheus, query);
            return ShowsANumber(result);
          },
          std::chrono::seconds(20)))
          << title << ": " << query << " gives " << result.dump();
    }
  }
  EXPECT_EQ(shown_gpu_panels, gpu_panels);

  // The call latency panel leaves out the streams (their time is the transfer's or the wait's).
  nlohmann::json latency;
  for (const auto& panel : dashboard.at("panels")) {
    if (!panel.at("title").get<std::string>().starts_with("Call latency")) continue;
    latency = Query(prometheus, std::regex_replace(panel.at("targets")[0].at("expr").get<std::string>(),
                                                   std::regex("\\$(server|worker)"), ".*"));
  }
  ASSERT_TRUE(latency.is_array());
  for (const auto& series : latency) {
    const auto method = series.at("metric").value("method", "");
    EXPECT_FALSE(std::regex_match(method, std::regex("Upload|Watch|Fetch|Report|PutBlobs|GetBlobs")))
        << method;
  }
}

}  // namespace
}  // namespace endorecon::testing
