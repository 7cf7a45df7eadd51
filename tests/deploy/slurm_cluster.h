// A real single-node Slurm for tests: Debian's munged, slurmctld and slurmd, started as root with
// their own key, socket, ports, state and spool folders under one temp folder, and stopped (jobs
// cancelled first) when the object goes. Commands (sbatch, squeue, scancel) find it through
// SLURM_CONF, which the constructor sets for this process and its children.
#pragma once

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "tests/integration/service_harness.h"

namespace endorecon::testing {

class SlurmCluster {
 public:
  // Starts the daemons in `dir` and waits (up to 30 s) for the node to be idle. When Slurm cannot
  // start here (not root, not installed, a daemon that will not come up), up() is false and
  // why_not() says why in one line.
  explicit SlurmCluster(const std::filesystem::path& dir);
  ~SlurmCluster();
  SlurmCluster(const SlurmCluster&) = delete;
  SlurmCluster& operator=(const SlurmCluster&) = delete;

  bool up() const { return why_not_.empty(); }
  const std::string& why_not() const { return why_not_; }
  // Runs a Slurm command (sbatch, squeue, ...) to completion.
  CliResult Command(const std::vector<std::string>& argv) const;
  // Cancels every job and waits (up to 30 s) until none is left.
  void CancelAll();

 private:
  void Start();
  std::string LogTail() const;

  std::filesystem::path dir_;
  std::string why_not_;
  std::unique_ptr<Process> munged_, slurmctld_, slurmd_;
};

}  // namespace endorecon::testing
