// A Prometheus file-based service discovery file (file_sd_configs) naming this worker's /metrics, for a
// Prometheus that cannot know where a batch allocation's workers run (Slurm places them on any node,
// on ports that differ per allocation): written when the worker starts serving, removed when it stops.
//
//   [{"targets": ["node17:9465"], "labels": {"endorecon_worker": "node17-slurm42-gpu0"}}]
#pragma once

#include <filesystem>
#include <string>

namespace endorecon::worker {

// The host a scraper reaches `metrics_host` by: this machine's name for a wildcard bind (0.0.0.0, ::).
std::string ScrapeHost(const std::string& metrics_host, const std::string& hostname);

class PrometheusTargetFile {
 public:
  // Writes `file` (atomically), readable by all (a Prometheus runs as a user of its own; the file
  // names a host and port, no secret), making its folder readable by all if it is not there. Throws
  // Error naming it when it cannot.
  PrometheusTargetFile(std::filesystem::path file, const std::string& host, int port,
                       const std::string& worker_id);
  // Removes it if it still holds what this one wrote (another worker given the same file since
  // keeps its target; found 2026-12-07). A failure is logged. A worker killed (kill -9, a node lost)
  // leaves its file, naming a port nobody serves, until the next worker of that file starts.
  ~PrometheusTargetFile();
  PrometheusTargetFile(const PrometheusTargetFile&) = delete;
  PrometheusTargetFile& operator=(const PrometheusTargetFile&) = delete;

 private:
  std::filesystem::path file_;
  std::string text_;  // what it wrote
};

}  // namespace endorecon::worker
