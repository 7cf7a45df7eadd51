// The server's data disk fills up: uploads that do not fit are refused with RESOURCE_EXHAUSTED
// naming the limit (before any byte, or at the chunk where a disk filled from elsewhere runs out),
// what is stored stays intact and verifiable, committed bytes are kept, and once space is freed the
// same upload resumes and completes on the same server. The data folder is a 16 MiB tmpfs. And a
// worker's scratch folder that fills up hands its job back rather than failing it; a worker whose
// results the full server refuses keeps them until space is freed there.
#include <gtest/gtest.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <random>

#include "common/error.h"
#include "common/file_download.h"
#include "common/sha256.h"
#include "tests/fuzz/message_stream.h"
#include "tests/integration/service_harness.h"
#include "tests/integration/small_filesystem.h"

namespace endorecon::testing {
namespace {
namespace fs = std::filesystem;

constexpr std::int64_t kMiB = 1 << 20;
constexpr std::size_t kChunk = 256 * 1024;

std::string RandomBytes(std::size_t n, unsigned seed) {
  std::mt19937 random(seed);
  std::string bytes(n, '\0');
  for (auto& c : bytes) c = static_cast<char>(random() & 0xff);
  return bytes;
}

v1::Manifest ManifestOf(const std::string& path, const std::string& bytes) {
  v1::Manifest manifest;
  auto* entry = manifest.add_files();
  entry->set_path(path);
  entry->set_size(static_cast<std::int64_t>(bytes.size()));
  entry->set_sha256(Sha256Hex(bytes));
  return manifest;
}

v1::UploadRequest Chunk(const std::string& path, std::size_t offset, const std::string& bytes) {
  v1::UploadRequest request;
  request.mutable_chunk()->set_path(path);
  request.mutable_chunk()->set_offset(static_cast<std::int64_t>(offset));
  request.mutable_chunk()->set_data(bytes.substr(offset, kChunk));
  return request;
}

v1::UploadStatus Query(Cluster& cluster, const v1::Manifest& manifest) {
  grpc::ClientContext context;
  v1::UploadStatus status;
  const grpc::Status rpc = cluster.stub().QueryUpload(&context, manifest, &status);
  EXPECT_TRUE(rpc.ok() || rpc.error_code() == grpc::StatusCode::RESOURCE_EXHAUSTED) << rpc.error_message();
  return status;
}

// Uploads `bytes` from `from` on one stream; `midway`, when given, runs once the first chunk is
// committed (the test fills the disk there).
grpc::Status Upload(Cluster& cluster, const std::string& path, const std::string& bytes, std::size_t from = 0,
                    const std::function<void()>& midway = {}) {
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(30));
  v1::UploadStatus status;
  auto writer = cluster.stub().Upload(&context, &status);
  v1::UploadRequest first;
  *first.mutable_manifest() = ManifestOf(path, bytes);
  writer->Write(first);
  for (std::size_t offset = from; offset < bytes.size(); offset += kChunk) {
    if (!writer->Write(Chunk(path, offset, bytes))) break;
    if (offset == from && midway) {
      WaitUntil([&] { return Query(cluster, first.manifest()).committed_bytes() > std::int64_t(from); },
                std::chrono::seconds(10));
      midway();
    }
  }
  writer->WritesDone();
  return writer->Finish();
}

TEST(FullDiskTest, UploadsThatDoNotFitAreRefusedWhatIsStoredSurvivesAndTheUploadResumesOnceSpaceIsFreed) {
  Cluster cluster({"--min-free-bytes", std::to_string(2 * kMiB)}, /*start=*/false);
  SmallFilesystem disk(cluster.data_dir(), 16 * kMiB);
  if (!disk.mounted()) GTEST_SKIP() << disk.why();
  cluster.StartServer();

  // Stored while there is room.
  const std::string kept = RandomBytes(kMiB, 1);
  ASSERT_TRUE(Upload(cluster, "kept.bin", kept).ok());
  ASSERT_TRUE(Query(cluster, ManifestOf("kept.bin", kept)).complete());

  // 3 MiB free, 2 MiB of them the reserve: a 2 MiB upload is refused before any byte is written.
  const fs::path filler = cluster.data_dir() / "filler";
  FillLeaving(filler, 3 * kMiB);
  const std::string big = RandomBytes(2 * kMiB, 2);
  const grpc::Status refused = Upload(cluster, "big.bin", big);
  EXPECT_EQ(refused.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED) << refused.error_message();
  EXPECT_NE(refused.error_message().find("--min-free-bytes"), std::string::npos) << refused.error_message();
  EXPECT_NE(refused.error_message().find("bytes free"), std::string::npos) << refused.error_message();
  EXPECT_EQ(Query(cluster, ManifestOf("big.bin", big)).committed_bytes(), 0);

  // With 5 MiB free it fits at first; the disk then fills from elsewhere while it streams: the
  // upload stops at that chunk with RESOURCE_EXHAUSTED and keeps what it committed.
  fs::remove(filler);
  FillLeaving(filler, 5 * kMiB);
  const grpc::Status stopped =
      Upload(cluster, "big.bin", big, 0, [&] { FillLeaving(cluster.data_dir() / "filler2", kMiB / 2); });
  EXPECT_EQ(stopped.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED) << stopped.error_message();

  // What was stored before is intact: the server still vouches for it, and its bytes are the same.
  EXPECT_TRUE(Query(cluster, ManifestOf("kept.bin", kept)).complete());
  const std::string digest = Sha256Hex(kept);
  std::ifstream blob(cluster.data_dir() / "blobs" / digest.substr(0, 2) / digest, std::ios::binary);
  const std::string stored((std::istreambuf_iterator<char>(blob)), std::istreambuf_iterator<char>());
  EXPECT_EQ(stored, kept);

  // Space freed: the committed bytes are there (while the disk was full, asking was refused too),
  // the same server takes the rest from the committed size, and the blob verifies.
  fs::remove(filler);
  fs::remove(cluster.data_dir() / "filler2");
  const std::int64_t committed = Query(cluster, ManifestOf("big.bin", big)).committed_bytes();
  EXPECT_GE(committed, std::int64_t(kChunk));
  EXPECT_LT(committed, std::int64_t(big.size()));
  const grpc::Status resumed = Upload(cluster, "big.bin", big, std::size_t(committed));
  ASSERT_TRUE(resumed.ok()) << resumed.error_message();
  EXPECT_TRUE(Query(cluster, ManifestOf("big.bin", big)).complete());
}

// The limits' bad values are refused at start, naming the option.
TEST(FullDiskTest, ANegativeFreeSpaceLimitANonPositiveStallTimeoutOrATooSmallThreadCapIsRefusedAtStart) {
  TempDir dir("limits");
  const std::string server =
      BuiltBinary("server/endorecon-server") + " --data-dir " + (dir / "data").string();
  const std::string worker =
      BuiltBinary("worker/runtime/endorecon-worker") + " serve --work-dir " + (dir / "work").string();
  for (const auto& [command, option] : std::vector<std::pair<std::string, std::string>>{
           {server + " --min-free-bytes -1", "--min-free-bytes"},
           {server + " --stall-timeout 0", "--stall-timeout"},
           {server + " --max-threads 4", "--max-threads"},
           {server + " --max-threads many", "--max-threads"},
           // CLI11 read 0x3 as 3, and 011 as 9 (found 2026-12-07).
           {server + " --max-attempts 0x3", "--max-attempts"},
           {worker + " --min-free-bytes -5", "--min-free-bytes"},
           // Taken until 2026-12-05: gRPC listened on a port of its choosing for 99999.
           {server + " --max-upload-bytes -5", "--max-upload-bytes"},
           {server + " --listen 127.0.0.1:99999", "--listen"},
           {server + " --listen garbage", "--listen"},
           {server + " --health-listen 127.0.0.1:", "--health-listen"},
           // An exception's word ("stoi") and exit 1, a port past 65535 taken, a negative metrics
           // port taken as off (found 2026-12-07).
           {server + " --dicom-listen 127.0.0.1:abc", "--dicom-listen"},
           {server + " --dicom-listen 127.0.0.1:99999", "--dicom-listen"},
           {server + " --dicom-listen unix:/tmp/scp", "--dicom-listen"},
           {server + " --dicom-listen 127.0.0.1:0", "--dicom-listen"},  // no PACS could be told it
           {server + " --metrics-port -2", "--metrics-port"},
           {server + " --metrics-port 70000", "--metrics-port"}}) {
    const std::string output = Capture(command + " 2>&1; echo \"exit=$?\"");
    EXPECT_NE(output.find(option + ": "), std::string::npos) << command << "\n" << output;
    EXPECT_EQ(output.find("179769313486231570814527"), std::string::npos)
        << "the bound in words, not DBL_MAX";
    EXPECT_NE(output.find("exit=2"), std::string::npos) << command << "\n" << output;  // a usage error
  }
  EXPECT_FALSE(fs::exists(dir / "data" / "jobs.sqlite")) << "nothing started";
}

// A download into a folder that fills up says the disk is full (RESOURCE_EXHAUSTED, the system's
// words), keeps what arrived, and is not taken for data damaged in transit: found under
// AddressSanitizer, where a worker handed a checkpoint into a full scratch folder reported DATA_LOSS
// and the job lost an attempt for its disk.
TEST(FullDiskTest, ADownloadIntoAFullFolderSaysTheDiskIsFullNotThatTheDataWasDamaged) {
  TempDir dir("download");
  SmallFilesystem small(dir / "small", kMiB);
  if (!small.mounted()) GTEST_SKIP() << small.why();
  std::string bytes(3 * kMiB, '\0');
  std::mt19937 random(7);
  for (char& byte : bytes) byte = static_cast<char>(random());
  std::vector<v1::FileChunk> chunks;
  for (std::int64_t offset = 0; offset < std::int64_t(bytes.size()); offset += 256 * 1024) {
    v1::FileChunk chunk;
    if (offset == 0) {
      chunk.mutable_file()->set_path("checkpoint.bin");
      chunk.mutable_file()->set_size(std::int64_t(bytes.size()));
      chunk.mutable_file()->set_sha256(Sha256Hex(bytes));
    }
    chunk.set_offset(offset);
    chunk.set_data(bytes.substr(std::size_t(offset), 256 * 1024));
    chunks.push_back(chunk);
  }
  fuzz::ClientStreamOf<v1::FileChunk> stream(chunks);
  try {
    ReceiveFiles(stream, dir / "small");
    ADD_FAILURE() << "3 MiB fit in a 1 MiB filesystem";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kResourceExhausted) << e.what();
    EXPECT_NE(std::string(e.what()).find(std::strerror(ENOSPC)), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("checkpoint.bin.part"), std::string::npos) << e.what();
  }
  EXPECT_TRUE(fs::exists(dir / "small" / "checkpoint.bin.part")) << "what arrived is kept for the resume";
  EXPECT_FALSE(fs::exists(dir / "small" / "checkpoint.bin"));
}

// A worker whose scratch folder (a 3 MiB tmpfs: the job's checkpoint alone is larger) runs out of
// space hands the job back without counting an attempt, names its scratch folder, and leaves jobs to
// others for a while; a worker with room then finishes the job.
TEST(FullDiskTest, AWorkerWhoseScratchFillsHandsTheJobBackUncountedAndAnotherWorkerFinishesIt) {
  Cluster cluster;
  MakeClip(cluster.path("clip"));
  SmallFilesystem scratch(cluster.path("work-small"), 3 * kMiB);  // StartWorker's --work-dir for "small"
  if (!scratch.mounted()) GTEST_SKIP() << scratch.why();
  auto& small = cluster.StartWorker("small", {"--min-free-bytes", std::to_string(kMiB)});
  const auto id = cluster.Submit(cluster.path("clip"), {"--iterations", "30"});
  ASSERT_TRUE(WaitUntil([&] { return cluster.Job(id).error().find("scratch folder") != std::string::npos; },
                        std::chrono::seconds(120)))
      << cluster.ServerLog() << small.Log();
  const v1::Job requeued = cluster.Job(id);
  EXPECT_EQ(requeued.state(), v1::QUEUED) << requeued.error();
  EXPECT_EQ(requeued.attempts(), 0) << "a full disk is not the job's attempt";
  EXPECT_NE(requeued.error().find(cluster.path("work-small").string()), std::string::npos)
      << requeued.error();

  cluster.StartWorker("roomy");
  const v1::Job done = cluster.WaitForState(id, v1::SUCCEEDED, std::chrono::seconds(120));
  EXPECT_EQ(done.state(), v1::SUCCEEDED) << done.error() << cluster.ServerLog();
  EXPECT_EQ(done.attempts(), 0);
  EXPECT_EQ(done.worker_id(), "roomy");
}

// A server started on a disk with less free than its reserve says so at once.
TEST(FullDiskTest, AStartBelowTheReserveIsWarnedOf) {
  Cluster cluster({"--min-free-bytes", std::to_string(64 * kMiB)}, false);
  SmallFilesystem data(cluster.data_dir(), 16 * kMiB);
  if (!data.mounted()) GTEST_SKIP() << data.why();
  cluster.StartServer();
  EXPECT_NE(cluster.ServerLog().find("less than --min-free-bytes 67108864: clients' uploads are refused"),
            std::string::npos)
      << cluster.ServerLog();
}

// A server whose data disk is full when a worker's results are ready: the worker keeps them and
// the lease, and sends them once space is freed; the job succeeds with no attempt counted. (It failed
// after three attempts, each training again, within a minute; found 2026-12-07.)
TEST(FullDiskTest, ResultsTheFullServerRefusesWaitOnTheWorkerUntilSpaceIsFreedOrItStops) {
  Cluster cluster({"--min-free-bytes", std::to_string(8 * kMiB)}, false);
  SmallFilesystem data(cluster.data_dir(), 24 * kMiB);
  if (!data.mounted()) GTEST_SKIP() << data.why();
  cluster.StartServer();
  MakeClip(cluster.path("clip"));
  const auto id = cluster.Submit(cluster.path("clip"), {"--iterations", "30"});
  // Less free than a worker's reserve (a quarter of --min-free-bytes), room left for the job store.
  FillLeaving(cluster.data_dir() / "filler", kMiB);
  auto& worker = cluster.StartWorker("w");
  ASSERT_TRUE(
      WaitUntil([&] { return worker.Log().find("the results wait on this worker") != std::string::npos; },
                std::chrono::seconds(120)))
      << worker.Log() << cluster.ServerLog();
  const v1::Job waiting = cluster.Job(id);
  EXPECT_EQ(waiting.state(), v1::RUNNING) << waiting.error();
  EXPECT_EQ(waiting.attempts(), 0);
  // The job's progress and the server's log say so (`status` said only "uploading the results").
  EXPECT_TRUE(WaitUntil([&] { return cluster.Job(id).progress().phase() == "upload-wait"; },
                        std::chrono::seconds(10)));
  EXPECT_NE(cluster.ServerLog().find("a worker's results or checkpoint were refused"), std::string::npos)
      << cluster.ServerLog();
  // A worker stopped meanwhile (SIGTERM) does not wait for the space: it hands the job back,
  // uncounted (it waited on until the disk was freed; found 2026-12-07).
  const auto stop_started = std::chrono::steady_clock::now();
  cluster.StopWorker("w", SIGTERM);
  EXPECT_LT(std::chrono::steady_clock::now() - stop_started, std::chrono::seconds(20)) << worker.Log();
  const v1::Job handed_back = cluster.Job(id);
  EXPECT_EQ(handed_back.state(), v1::QUEUED) << handed_back.error();
  EXPECT_EQ(handed_back.attempts(), 0);

  fs::remove(cluster.data_dir() / "filler");
  auto& second = cluster.StartWorker("w2");
  const v1::Job done = cluster.WaitForState(id, v1::SUCCEEDED, std::chrono::seconds(90));
  EXPECT_EQ(done.state(), v1::SUCCEEDED) << done.error() << second.Log();
  EXPECT_EQ(done.attempts(), 0);
}

}  // namespace
}  // namespace endorecon::testing
