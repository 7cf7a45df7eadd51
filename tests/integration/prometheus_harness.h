// A real Prometheus (the Debian package) scraping a test cluster: the server's /metrics and one
// worker's, each second, its data in the cluster's folder.
#pragma once

#include <memory>
#include <string>

#include "tests/integration/service_harness.h"

namespace endorecon::testing {

class PrometheusScraper {
 public:
  // Starts Prometheus once `worker` serves its metrics; returns when it has scraped both targets
  // (or throws saying why, with its log).
  PrometheusScraper(Cluster& cluster, const std::string& worker);

  // The HTTP API's answer (JSON) to the instant query `expression`; "" when it does not answer.
  std::string Query(const std::string& expression) const;
  std::string Log() const { return process_->Log(); }

 private:
  int port_ = 0;
  std::unique_ptr<Process> process_;
};

}  // namespace endorecon::testing
