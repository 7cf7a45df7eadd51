#include "worker/runtime/prometheus_target_file.h"

#include <spdlog/spdlog.h>

#include <nlohmann/json.hpp>
#include <system_error>
#include <utility>

#include "common/error.h"
#include "common/file_write.h"

namespace endorecon::worker {

std::string ScrapeHost(const std::string& metrics_host, const std::string& hostname) {
  if (metrics_host == "0.0.0.0" || metrics_host == "::" || metrics_host == "[::]") return hostname;
  // An IPv6 address is bracketed in a target, as in a URL.
  if (metrics_host.find(':') != std::string::npos && metrics_host.front() != '[')
    return "[" + metrics_host + "]";
  return metrics_host;
}

PrometheusTargetFile::PrometheusTargetFile(std::filesystem::path file, const std::string& host, int port,
                                           const std::string& worker_id)
    : file_(std::move(file)) {
  const nlohmann::json targets = nlohmann::json::array(
      {{{"targets", {host + ":" + std::to_string(port)}}, {"labels", {{"endorecon_worker", worker_id}}}}});
  WriteFile(file_, targets.dump() + "\n", "Prometheus target file");
}

PrometheusTargetFile::~PrometheusTargetFile() {
  std::error_code error;
  std::filesystem::remove(file_, error);
  if (error) spdlog::warn("cannot remove the Prometheus target file {}: {}", file_.string(), error.message());
}

}  // namespace endorecon::worker
