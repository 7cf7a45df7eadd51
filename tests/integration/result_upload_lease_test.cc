// A worker whose results wait to be uploaded (every upload slot of the server taken by clients'
// uploads, or a slow link) keeps its lease while they wait. Its heartbeats ended with the
// reconstruction, so a wait longer than the lease's time let the lease expire: the job went back to
// the queue with an attempt counted, the finished results were refused and thrown away, and the job
// trained again, or failed once its attempts were spent (found by reading the runner, 2026-12-05).
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <thread>

#include "common/error.h"
#include "common/manifest.h"
#include "tests/integration/audit_reader.h"
#include "tests/integration/leased_worker.h"
#include "tests/integration/sanitizer_build.h"
#include "tests/integration/service_harness.h"
#include "tests/integration/upload_requests.h"
#include "worker/runtime/job_runner.h"

namespace endorecon::testing {
namespace {

TEST(ResultUploadLeaseTest, ResultsThatWaitLongerThanTheLeaseForAnUploadSlotAreKept) {
  Cluster cluster({"--max-uploads", "1", "--max-attempts", "1"});  // the harness's lease: 3 s
  MakeClip(cluster.path("clip"));
  const auto id = cluster.Submit(cluster.path("clip"), {"--iterations", "5"});

  auto [device, client, lease] = LeaseAsWorker(cluster, "waiting-uploader");
  ASSERT_TRUE(lease.has_value()) << cluster.ServerLog();
  ASSERT_EQ(lease->job().id(), id);

  worker::RunnerSettings settings;
  settings.work_dir = cluster.path("scratch");
  settings.heartbeat = std::chrono::milliseconds(300);
  settings.min_free_bytes = 0;
  const auto results = settings.work_dir / id / "out" / "metrics.json";  // among the last written
  bool waited = false;
  std::thread holder([&] {
    // Once training's last checkpoint is uploaded, a client's upload takes the server's only slot:
    // its manifest is in, its bytes do not come. The slot is given back twice the lease's time (3 s)
    // after the results are written.
    WaitUntil([&] { return !cluster.Job(id).checkpoint().sha256().empty(); }, std::chrono::seconds(120));
    grpc::ClientContext holding;
    v1::UploadStatus held_status;
    const auto held = cluster.stub().Upload(&holding, &held_status);
    held->Write(ManifestOf({Entry("held.bin", "bytes that never come")}));
    WaitUntil([&] { return std::filesystem::exists(results); }, std::chrono::seconds(120));
    std::this_thread::sleep_for(std::chrono::milliseconds(7000 * kSlowdown));
    waited = cluster.Job(id).state() != v1::SUCCEEDED;  // the results are still waiting for the slot
    holding.TryCancel();
    held->Finish();
  });
  worker::WorkerMetrics metrics("", {device});
  const std::atomic<bool> shutting_down{false};
  EXPECT_NO_THROW(worker::RunLeasedJob(*client, *lease, device, settings, metrics, shutting_down));
  holder.join();

  EXPECT_TRUE(waited) << "the results did not wait for the upload slot: the test tested nothing";
  const v1::Job job = cluster.Job(id);
  EXPECT_EQ(job.state(), v1::SUCCEEDED) << job.error() << "\n" << cluster.ServerLog();
  EXPECT_EQ(job.attempts(), 0);
  EXPECT_GT(job.result().files_size(), 0);
}

// A worker whose token serves one tenant shows its results are its own by uploading them (proof of
// possession, server/blob_holders.h); the server keeps that in memory only, so a restart between the
// upload and the Complete made the Complete refuse them as not uploaded, and the job went back with an
// attempt counted after its whole training. CompleteWithResults sends them again, once.
TEST(ResultUploadLeaseTest, AScopedWorkersResultsForgottenByARestartAreSentAgain) {
  Cluster cluster({}, false);
  const auto admin = MakeCredentials(cluster, "", "admin", "", "ops");
  const auto alice = MakeCredentials(cluster, "", "client", "radiology", "alice");
  const auto node = MakeCredentials(cluster, "", "worker", "radiology", "node-r");
  cluster.UseCredentials(admin);
  cluster.StartServer();
  MakeClip(cluster.path("clip"));
  auto submit = alice.CliFlags();
  submit.insert(submit.end(), {"submit", cluster.path("clip").string(), "--iterations", "5"});
  ASSERT_EQ(RunCli(cluster.address(), submit).exit_code, 0);

  worker::Device device;
  device.name = "cpu0";
  device.kind = "cpu";
  device.threads = 1;
  ChannelSecurity security;
  security.token_file = node.token_file;
  worker::WorkerClient client(cluster.address(), security, "w-radiology", std::chrono::seconds(10));
  client.Register("localhost", {device});
  const auto lease = client.Lease(device.name, std::chrono::seconds(10));
  ASSERT_TRUE(lease.has_value()) << cluster.ServerLog();
  const auto results = cluster.path("results");
  std::filesystem::create_directories(results);
  WriteBytes(results / "metrics.json", "{\"psnr\": 30.25, \"job\": \"" + lease->job().id() + "\"}");
  v1::CompleteRequest complete;
  complete.set_lease_id(lease->lease_id());
  *complete.mutable_result() = ManifestOfDirectory(results);
  client.PutFiles(results, complete.result());

  cluster.KillServer(SIGKILL);  // the running job's lease is kept for one lease time after the start
  cluster.StartServer();
  const auto refused = [&] {
    try {
      client.Complete(complete);
    } catch (const Error& e) {
      return e.code() == ErrorCode::kFailedPrecondition &&
             std::string(e.what()).find("not uploaded yet") != std::string::npos;
    }
    return false;
  };
  ASSERT_TRUE(refused()) << "the restarted server took results it had not seen sent: the test tests nothing";
  const auto puts = [&] {
    return AuditFind(AuditLines(cluster.data_dir() / "audit.jsonl"), "PutBlobs", "OK", "node-r").size();
  };
  const auto before = puts();
  const v1::Job job = client.CompleteWithResults(results, complete);
  EXPECT_EQ(job.state(), v1::SUCCEEDED) << job.error();
  EXPECT_EQ(job.attempts(), 0);
  EXPECT_EQ(puts(), before + 1) << "the results were sent again";
}

}  // namespace
}  // namespace endorecon::testing
