#include "worker/runtime/prometheus_target_file.h"

#include <spdlog/spdlog.h>

#include <fstream>
#include <nlohmann/json.hpp>
#include <system_error>
#include <utility>
#include <vector>

#include "common/error.h"
#include "common/file_write.h"

namespace endorecon::worker {

namespace {

// The file's bytes, or "" when it cannot be read or is larger than a target file.
std::string ReadIfSmall(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::string text(4096, '\0');
  in.read(text.data(), static_cast<std::streamsize>(text.size()));
  text.resize(static_cast<std::size_t>(in.gcount()));
  return in.eof() ? text : std::string();
}

}  // namespace

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
  namespace fs = std::filesystem;
  const nlohmann::json targets = nlohmann::json::array(
      {{{"targets", {host + ":" + std::to_string(port)}}, {"labels", {{"endorecon_worker", worker_id}}}}});
  text_ = targets.dump() + "\n";
  const auto folder = file_.parent_path().empty() ? fs::path(".") : file_.parent_path();
  std::error_code error;
  // Each folder made is opened to all, not the last alone: the worker's umask (077) made the ones
  // above it 0700, which Prometheus could not pass (found 2026-12-07).
  std::vector<fs::path> missing;
  for (fs::path at = fs::absolute(folder, error); !at.empty() && !fs::exists(at, error);
       at = at.parent_path()) {
    missing.push_back(at);
    if (at == at.parent_path()) break;
  }
  for (auto it = missing.rbegin(); it != missing.rend(); ++it) {
    if (fs::create_directory(*it, error)) fs::permissions(*it, fs::perms(0755), error);
  }
  WriteFile(file_, text_, "Prometheus target file");
  fs::permissions(file_, fs::perms(0644), error);
}

PrometheusTargetFile::~PrometheusTargetFile() {
  std::error_code error;
  if (ReadIfSmall(file_) != text_) return;  // another worker's now, or gone
  std::filesystem::remove(file_, error);
  if (error) spdlog::warn("cannot remove the Prometheus target file {}: {}", file_.string(), error.message());
}

}  // namespace endorecon::worker
