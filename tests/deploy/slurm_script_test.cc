// The Slurm batch script gives endorecon-worker only flags it has (the script's run on a real
// Slurm is slurm_batch_test.cc, which needs root).
#include <gtest/gtest.h>

#include <chrono>
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
// `environment`: more VAR=value words for the script; `dir`: where the fake srun and scancel go.
int BatchStatusWithWorker(const std::string& worker, std::string& log, const std::string& environment = "",
                          const fs::path& dir = {}) {
  TempDir own("sbatch");
  const fs::path bin = dir.empty() ? own.path() : dir;
  WriteBytes(bin / "srun",
             "#!/bin/bash\nwhile [ $# -gt 0 ] && [ \"${1#--}\" != \"$1\" ]; do shift; done\nexec \"$@\"\n");
  fs::permissions(bin / "srun", fs::perms::owner_all);
  const std::string command =
      "PATH='" + bin.string() + "':$PATH ENDORECON_SERVER=127.0.0.1:1 ENDORECON_WORKER=" + worker +
      " SLURM_JOB_ID=7 SLURM_CPUS_PER_TASK=1 TMPDIR='" + bin.string() + "' " + environment + " bash '" +
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

// One worker per GPU Slurm granted (SLURM_JOB_GPUS), not per GPU the submitting shell named
// (CUDA_VISIBLE_DEVICES, inherited under --export=ALL by a job without GPUs, made it a failed GPU job);
// metrics ports -1 and 0 go to every slot as they are (they became ports 1, 2, ...); each worker
// leaves when idle and, given the folder, keeps a Prometheus target there.
TEST(SlurmScriptTest, EachGrantedGpuGetsAWorkerWithItsPortIdleExitAndTarget) {
  std::string log;
  ASSERT_EQ(BatchStatusWithWorker("/bin/echo", log, "CUDA_VISIBLE_DEVICES=0,1"), 0) << log;
  EXPECT_NE(log.find("--devices cpu"), std::string::npos) << log;
  EXPECT_NE(log.find("--exit-when-idle 600"), std::string::npos) << log;
  EXPECT_EQ(log.find("--prometheus-target-file"), std::string::npos) << log;

  ASSERT_EQ(BatchStatusWithWorker("/bin/echo", log,
                                  "SLURM_JOB_GPUS=4,5 ENDORECON_METRICS_PORT=0 ENDORECON_IDLE_EXIT=0 "
                                  "ENDORECON_PROMETHEUS_TARGETS=/shared/targets"),
            0)
      << log;
  for (const std::string slot : {"gpu0", "gpu1"}) {
    const auto line = log.find("-slurm7-" + slot + " ");
    ASSERT_NE(line, std::string::npos) << log;
    const auto end = log.find('\n', line);
    const auto start = log.rfind('\n', line) + 1;
    const auto words = log.substr(start, end - start);
    EXPECT_NE(words.find("--devices 0 "), std::string::npos) << words;
    EXPECT_NE(words.find("--metrics-port 0 "), std::string::npos) << words;
    EXPECT_NE(words.find("--exit-when-idle 0 "), std::string::npos) << words;
    EXPECT_NE(words.find("--prometheus-target-file /shared/targets/"), std::string::npos) << words;
    EXPECT_NE(words.find("-slurm7-" + slot + ".json"), std::string::npos) << words;
  }
}

// A worker that fails while another runs is named at once and the others are stopped (they hand
// their jobs back): the script waited on the slots in turn, so a failed slot's GPU sat idle,
// unreported, until the first slot's worker ended.
TEST(SlurmScriptTest, AFailingWorkerIsNamedAtOnceAndTheOthersStopped) {
  TempDir dir("sbatch");
  const auto worker = dir / "fake-worker";
  WriteBytes(worker,
             "#!/bin/bash\ncase \"$*\" in *-gpu1\\ *) exit 3;; esac\n"
             "sleep 60 & trap 'kill $!; echo handed back; exit 0' TERM\nwait\n");
  fs::permissions(worker, fs::perms::owner_all);
  // scancel --signal=TERM signals the job steps' tasks: here, the fake workers.
  WriteBytes(dir / "scancel", "#!/bin/bash\npkill -TERM -f '^/bin/bash " + worker.string() + " serve'\n");
  fs::permissions(dir / "scancel", fs::perms::owner_all);
  const auto started = std::chrono::steady_clock::now();
  std::string log;
  EXPECT_EQ(BatchStatusWithWorker(worker.string(), log, "SLURM_JOB_GPUS=0,1", dir.path()), 3) << log;
  EXPECT_LT(std::chrono::steady_clock::now() - started, std::chrono::seconds(30)) << log;
  EXPECT_NE(log.find("endorecon-worker for gpu1 exited with status 3"), std::string::npos) << log;
  EXPECT_NE(log.find("handed back"), std::string::npos) << log;
}

}  // namespace
}  // namespace endorecon::testing
