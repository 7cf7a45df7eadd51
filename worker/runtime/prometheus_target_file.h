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
  // Writes `file` (atomically, making its folder). Throws Error naming it when it cannot.
  PrometheusTargetFile(std::filesystem::path file, const std::string& host, int port,
                       const std::string& worker_id);
  // Removes it (a failure is logged).
  ~PrometheusTargetFile();
  PrometheusTargetFile(const PrometheusTargetFile&) = delete;
  PrometheusTargetFile& operator=(const PrometheusTargetFile&) = delete;

 private:
  std::filesystem::path file_;
};

}  // namespace endorecon::worker
