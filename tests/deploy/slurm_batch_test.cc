// deploy/slurm/endorecon-worker.sbatch on a real single-node Slurm: sbatch starts a worker that
// reaches a TLS server on loopback with its client certificate and worker token, leases a job and
// finishes it; scancel hands the allocation back.
#include <gtest/gtest.h>

#include "tests/deploy/slurm_cluster.h"
#include "tests/integration/service_harness.h"
#include "tests/integration/test_pki.h"

namespace endorecon::testing {
namespace {

TEST(SlurmBatchTest, SbatchStartsAWorkerThatFinishesAJob) {
  TempDir slurm_dir("slurm");
  SlurmCluster slurm(slurm_dir.path());
  if (!slurm.up()) GTEST_SKIP() << "Slurm cannot start here: " << slurm.why_not();

  TempDir pki_dir("pki");
  const TestPki pki(pki_dir.path());
  Cluster cluster(ServerTlsFlags(pki), false);
  const auto worker_token = MakeCredentials(cluster, "", "worker", "", "slurm-node").token_file;
  cluster.UseCredentials(MakeCredentials(cluster, pki.ca_cert.string(), "admin", "", "ops"));
  cluster.StartServer();
  // The script asks for 4 V100s, 8 CPUs a task and 96 GB; this node has none of that, so the
  // command line shrinks the request (no GPU: the script starts one CPU worker).
  const std::string script = std::string(ENDORECON_SOURCE_DIR) + "/deploy/slurm/endorecon-worker.sbatch";
  const auto sbatch = [&](const std::string& environment) {
    const auto submitted = slurm.Command(
        {"/usr/bin/sbatch", "--parsable", "--gres=none", "--ntasks=1", "--cpus-per-task=1", "--mem=1G",
         "--time=10", "--chdir=" + cluster.path("").string(),
         "--output=" + cluster.path("slurm-%j.log").string(),
         "--export=ALL,ENDORECON_SERVER=" + cluster.address() +
             ",ENDORECON_WORKER=" + BuiltBinary("worker/runtime/endorecon-worker") +
             ",ENDORECON_CA=" + pki.ca_cert.string() + ",ENDORECON_TLS_CERT=" + pki.worker_cert.string() +
             ",ENDORECON_TLS_KEY=" + pki.worker_key.string() + ",ENDORECON_TOKEN_FILE=" + worker_token +
             ",ENDORECON_METRICS_HOST=127.0.0.1,ENDORECON_METRICS_PORT=" + std::to_string(FreePort()) +
             ",TMPDIR=" + cluster.path("").string() + environment,
         script});
    EXPECT_EQ(submitted.exit_code, 0) << submitted.err;
    return submitted.out.substr(0, submitted.out.find_first_of(";\n"));
  };
  const auto queue_empty = [&] {
    return WaitUntil(
        [&] {
          return slurm.Command({"/usr/bin/squeue", "-h"}).out.empty();
        },
        std::chrono::seconds(60));
  };

  // An empty queue gives the allocation back (ENDORECON_IDLE_EXIT) instead of holding it to its time
  // limit; while it served, its worker kept a Prometheus target in the folder given, gone after.
  const auto idle_job =
      sbatch(",ENDORECON_IDLE_EXIT=2,ENDORECON_PROMETHEUS_TARGETS=" + cluster.path("targets").string());
  EXPECT_TRUE(queue_empty()) << "the idle allocation was held";
  const auto idle_log = ReadBytes(cluster.path("slurm-" + idle_job + ".log"));
  EXPECT_NE(idle_log.find("no job for 2 s (--exit-when-idle): stopping"), std::string::npos) << idle_log;
  EXPECT_NE(idle_log.find("Prometheus target 127.0.0.1:"), std::string::npos) << idle_log;
  EXPECT_TRUE(std::filesystem::is_empty(cluster.path("targets")));

  MakeClip(cluster.path("clip"));
  const auto id = cluster.Submit(cluster.path("clip"), {"--iterations", "20"});
  const auto slurm_job = sbatch("");

  const auto job = cluster.WaitForState(id, v1::SUCCEEDED, std::chrono::seconds(120));
  const std::string batch_log = ReadBytes(cluster.path("slurm-" + slurm_job + ".log"));
  ASSERT_EQ(job.state(), v1::SUCCEEDED) << job.error() << "\n" << batch_log << cluster.ServerLog();
  EXPECT_NE(job.worker_id().find("-slurm" + slurm_job + "-cpu"), std::string::npos) << job.worker_id();
  EXPECT_GT(job.result().files_size(), 0);

  // The time limit's warning (--signal=B:TERM@120: SIGTERM to the batch shell alone) reaches the
  // worker, which hands its job back whole; the script's TERM to srun made srun kill the worker, and
  // the job lost an attempt to its lease's expiry (found 2026-12-06). Then the allocation ends and
  // its scratch folder, which held the clip, goes with it.
  const auto running = cluster.Submit(cluster.path("clip"), {"--time-budget", "600"});
  cluster.WaitForState(running, v1::RUNNING, std::chrono::seconds(60));
  ASSERT_EQ(slurm.Command({"/usr/bin/scancel", "--batch", "--signal=TERM", slurm_job}).exit_code, 0);
  const auto handed_back = cluster.WaitForState(running, v1::QUEUED, std::chrono::seconds(60));
  EXPECT_EQ(handed_back.state(), v1::QUEUED)
      << ReadBytes(cluster.path("slurm-" + slurm_job + ".log")) << cluster.ServerLog();
  EXPECT_EQ(handed_back.attempts(), 0) << handed_back.error();
  EXPECT_TRUE(queue_empty());
  EXPECT_FALSE(std::filesystem::exists(cluster.path("endorecon-" + slurm_job)));

  slurm.CancelAll();
  EXPECT_TRUE(slurm.Command({"/usr/bin/squeue", "-h"}).out.empty());
}

}  // namespace
}  // namespace endorecon::testing
