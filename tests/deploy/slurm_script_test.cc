// The Slurm batch script gives endorecon-worker only flags it has (the script's run on a real
// Slurm is slurm_batch_test.cc, which needs root).
#include <gtest/gtest.h>

#include <sstream>

#include "tests/deploy/deploy_files.h"

namespace endorecon::testing {
namespace {

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

}  // namespace
}  // namespace endorecon::testing
