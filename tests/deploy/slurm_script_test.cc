// The Slurm batch script gives endorecon-worker only flags it has (the script's run on a real
// Slurm is slurm_batch_test.cc, which needs root).
#include <gtest/gtest.h>

#include <sstream>

#include "tests/deploy/deploy_files.h"

namespace endorecon::testing {
namespace {

namespace fs = std::filesystem;

TEST(SlurmScriptTest, TheWorkerGetsOnlyFlagsItHas) {
  const std::string script = ReadBytes(SourcePath("deploy/slurm/endorecon-worker.sbatch"));
  // The worker's command line: the `"$WORKER" serve` line and its continuations, and the security flags.
  std::string worker_words;
  std::istringstream lines(script);
  bool in_serve = false;
  for (std::string line; std::getline(lines, line);) {
    in_serve = in_serve || line.find("\"$WORKER\" serve") != std::string::npos;
    if (in_serve || line.find("security+=(") != std::string::npos) worker_words += line + "\n";
    if (in_serve && line.find('&') != std::string::npos) in_serve = false;
  }
  const auto accepted = AcceptedFlags(BinaryNamed("endorecon-worker"), "serve");
  const std::regex flag("--[a-z][a-z0-9-]*");
  std::set<std::string> used;
  for (auto it = std::sregex_iterator(worker_words.begin(), worker_words.end(), flag);
       it != std::sregex_iterator(); ++it) {
    used.insert(it->str());
    EXPECT_TRUE(accepted.count(it->str())) << "endorecon-worker serve has no " << it->str();
  }
  for (const std::string expected : {"--server", "--devices", "--ca", "--tls-cert", "--tls-key",
                                     "--token-file", "--metrics-port", "--work-dir", "--id"})
    EXPECT_TRUE(used.count(expected)) << "the script does not pass " << expected;
}

// The batch job's exit status is its workers': a worker that exits at once (refused credentials, a
// taken port) failed the batch job, which still ended 0. Run outside Slurm, with an `srun` that drops
// its options and runs the command.
int BatchStatusWithWorker(const std::string& worker, std::string& log) {
  TempDir dir("sbatch");
  WriteBytes(dir / "srun",
             "#!/bin/bash\nwhile [ $# -gt 0 ] && [ \"${1#--}\" != \"$1\" ]; do shift; done\nexec \"$@\"\n");
  fs::permissions(dir / "srun", fs::perms::owner_all);
  const std::string command =
      "PATH='" + dir.path().string() + "':$PATH ENDORECON_SERVER=127.0.0.1:1 ENDORECON_WORKER=" + worker +
      " SLURM_JOB_ID=7 SLURM_CPUS_PER_TASK=1 TMPDIR='" + dir.path().string() + "' bash '" +
      SourcePath("deploy/slurm/endorecon-worker.sbatch").string() + "' 2>&1";
  log = Capture(command + "; echo rc=$?");
  const auto at = log.rfind("rc=");
  return std::stoi(log.substr(at + 3));
}

TEST(SlurmScriptTest, TheBatchJobFailsWhenAWorkerFails) {
  std::string log;
  EXPECT_EQ(BatchStatusWithWorker("/bin/false", log), 1) << log;
  EXPECT_NE(log.find("endorecon-worker for cpu exited with status 1"), std::string::npos) << log;
  EXPECT_EQ(BatchStatusWithWorker("/bin/true", log), 0) << log;
}

}  // namespace
}  // namespace endorecon::testing
