#include "tests/integration/prometheus_harness.h"

#include <fstream>
#include <stdexcept>

namespace endorecon::testing {

PrometheusScraper::PrometheusScraper(Cluster& cluster, const std::string& worker) {
  if (!WaitUntil([&] { return cluster.worker_metrics_port(worker) > 0; }))
    throw std::runtime_error("worker " + worker + " serves no metrics");
  port_ = FreePort();
  const auto config = cluster.path("prometheus.yml");
  std::ofstream(config)
      << "global:\n  scrape_interval: 1s\n"
      << "scrape_configs:\n"
      << "  - job_name: endorecon-server\n    static_configs:\n      - targets: ['127.0.0.1:"
      << cluster.metrics_port() << "']\n"
      << "  - job_name: endorecon-worker\n    static_configs:\n      - targets: ['127.0.0.1:"
      << cluster.worker_metrics_port(worker) << "']\n";
  process_ = std::make_unique<Process>(
      std::vector<std::string>{"/usr/bin/prometheus", "--config.file=" + config.string(),
                               "--storage.tsdb.path=" + cluster.path("tsdb").string(),
                               "--web.listen-address=127.0.0.1:" + std::to_string(port_)},
      cluster.path("prometheus.log"));
  if (!WaitUntil([&] { return Query("count(up == 1)").find(",\"2\"]") != std::string::npos; }))
    throw std::runtime_error("Prometheus did not scrape the server and the worker: " + Log());
}

std::string PrometheusScraper::Query(const std::string& expression) const {
  return Capture("curl -s --max-time 5 'http://127.0.0.1:" + std::to_string(port_) +
                 "/api/v1/query' --data-urlencode 'query=" + expression + "'");
}

}  // namespace endorecon::testing
