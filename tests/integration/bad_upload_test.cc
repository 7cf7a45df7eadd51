// Every malformed upload is rejected with the status gRPC intends, and nothing half-written
// becomes visible: no blob appears unless all its bytes arrived and its SHA-256 matched.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <set>
#include <string>
#include <thread>

#include "common/clip_files.h"
#include "common/npy.h"
#include "common/sha256.h"
#include "tests/integration/service_harness.h"
#include "tests/integration/upload_requests.h"

namespace endorecon::testing {
namespace {
namespace fs = std::filesystem;

struct Outcome {
  grpc::Status status;
  v1::UploadStatus upload;
};

// Sends `requests` on one Upload stream; `cancel` ends it abruptly instead of cleanly.
Outcome Send(Cluster& cluster, const std::vector<v1::UploadRequest>& requests, bool cancel = false) {
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(20));
  Outcome outcome;
  auto writer = cluster.stub().Upload(&context, &outcome.upload);
  for (const auto& request : requests) {
    if (!writer->Write(request)) break;
  }
  if (cancel) {
    // Let the server take the chunks in before the stream is cut.
    const auto& manifest = requests.front().manifest();
    WaitUntil(
        [&] {
          grpc::ClientContext query;
          v1::UploadStatus status;
          cluster.stub().QueryUpload(&query, manifest, &status);
          return status.committed_bytes() > 0;
        },
        std::chrono::seconds(10));
    context.TryCancel();
  } else {
    writer->WritesDone();
  }
  outcome.status = writer->Finish();
  return outcome;
}

int CountFiles(const fs::path& dir) {
  if (!fs::exists(dir)) return 0;
  int count = 0;
  for (const auto& entry : fs::recursive_directory_iterator(dir)) count += entry.is_regular_file() ? 1 : 0;
  return count;
}

class BadUploadTest : public ::testing::Test {
 protected:
  Cluster cluster_{{"--max-upload-bytes", "1000000"}};
  int Blobs() { return CountFiles(cluster_.data_dir() / "blobs"); }
  int Partials() { return CountFiles(cluster_.data_dir() / "partial"); }
};

TEST_F(BadUploadTest, WrongChecksumIsDataLossAndLeavesNothing) {
  auto entry = Entry("images/000000.png", "the bytes the client promised");
  const auto outcome =
      Send(cluster_, {ManifestOf({entry}), Chunk(entry.path(), 0, "the bytes that really arrive!")});
  EXPECT_EQ(outcome.status.error_code(), grpc::StatusCode::DATA_LOSS) << outcome.status.error_message();
  EXPECT_NE(outcome.status.error_message().find("images/000000.png"), std::string::npos);
  EXPECT_EQ(Blobs(), 0);
  EXPECT_EQ(Partials(), 0);
}

TEST_F(BadUploadTest, TruncatedStreamKeepsCommittedBytesAndPromotesNothing) {
  const std::string bytes(300000, 'x');
  const auto entry = Entry("clip.bin", bytes);
  const auto cut =
      Send(cluster_, {ManifestOf({entry}), Chunk(entry.path(), 0, bytes.substr(0, 100000))}, true);
  EXPECT_FALSE(cut.status.ok());
  EXPECT_EQ(Blobs(), 0);
  v1::Manifest manifest;
  *manifest.add_files() = entry;
  v1::UploadStatus status;
  // The cut stream's handler may still be writing the chunk it received when the client's cut
  // returns (a query then sees the partial file part-written: 65,536 bytes once on a loaded
  // machine); what the server received is committed once it has, within seconds.
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  do {
    grpc::ClientContext query;
    ASSERT_TRUE(cluster_.stub().QueryUpload(&query, manifest, &status).ok());
    if (status.files(0).committed() == 100000) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  } while (std::chrono::steady_clock::now() < deadline);
  EXPECT_EQ(status.files(0).committed(), 100000);
  EXPECT_FALSE(status.complete());
  // The client continues from the committed size and the blob appears. Until the cut stream's
  // handler has let go of the file (a loaded machine may take seconds to sync it) the server skips
  // its chunks and says the upload is incomplete; the client then asks again, as the CLI does.
  Outcome rest;
  for (int attempt = 0; attempt < 10 && !rest.upload.complete(); ++attempt) {
    if (attempt > 0) std::this_thread::sleep_for(std::chrono::milliseconds(500));
    rest = Send(cluster_, {ManifestOf({entry}), Chunk(entry.path(), 100000, bytes.substr(100000))});
    ASSERT_TRUE(rest.status.ok()) << rest.status.error_message();
  }
  EXPECT_TRUE(rest.upload.complete());
  EXPECT_EQ(Blobs(), 1);
  EXPECT_EQ(Partials(), 0);
}

TEST_F(BadUploadTest, ChunkNotContinuingTheCommittedBytesIsRejected) {
  const auto entry = Entry("a.bin", "0123456789");
  const auto outcome = Send(cluster_, {ManifestOf({entry}), Chunk("a.bin", 4, "456789")});
  EXPECT_EQ(outcome.status.error_code(), grpc::StatusCode::FAILED_PRECONDITION)
      << outcome.status.error_message();
  EXPECT_EQ(Blobs(), 0);
}

TEST_F(BadUploadTest, EscapingOrAbsolutePathsAreInvalidAndNamed) {
  for (const std::string path : {"../x", "images/../../etc/passwd", "/etc/passwd"}) {
    const auto entry = Entry(path, "data");
    const auto outcome = Send(cluster_, {ManifestOf({entry}), Chunk(path, 0, "data")});
    EXPECT_EQ(outcome.status.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << path;
    EXPECT_NE(outcome.status.error_message().find("'" + path + "'"), std::string::npos)
        << outcome.status.error_message();
  }
  EXPECT_EQ(Blobs(), 0);
  EXPECT_EQ(Partials(), 0);
}

TEST_F(BadUploadTest, OverTheSizeLimitIsResourceExhaustedBeforeAnyByte) {
  v1::FileEntry huge;
  huge.set_path("huge.bin");
  huge.set_size(std::int64_t{50} << 30);  // 50 GiB
  huge.set_sha256(Sha256Hex("not really"));
  const auto outcome = Send(cluster_, {ManifestOf({huge}), Chunk("huge.bin", 0, std::string(1000, 'x'))});
  EXPECT_EQ(outcome.status.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED)
      << outcome.status.error_message();
  EXPECT_NE(outcome.status.error_message().find("--max-upload-bytes"), std::string::npos);
  EXPECT_NE(outcome.status.error_message().find("send fewer frames (`endorecon submit --frames"),
            std::string::npos)
      << "what to do";
  EXPECT_EQ(Partials(), 0);
  grpc::ClientContext query;
  v1::Manifest manifest;
  *manifest.add_files() = huge;
  v1::UploadStatus status;
  EXPECT_EQ(cluster_.stub().QueryUpload(&query, manifest, &status).error_code(),
            grpc::StatusCode::RESOURCE_EXHAUSTED);
}

TEST_F(BadUploadTest, MissingOrSecondManifestIsInvalid) {
  const auto entry = Entry("a.bin", "abc");
  const auto no_manifest = Send(cluster_, {Chunk("a.bin", 0, "abc")});
  EXPECT_EQ(no_manifest.status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(no_manifest.status.error_message().find("manifest"), std::string::npos);
  const auto empty = Send(cluster_, {});
  EXPECT_EQ(empty.status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  const auto second = Send(cluster_, {ManifestOf({entry}), ManifestOf({entry}), Chunk("a.bin", 0, "abc")});
  EXPECT_EQ(second.status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(second.status.error_message().find("second manifest"), std::string::npos);
  const auto unknown = Send(cluster_, {ManifestOf({entry}), Chunk("b.bin", 0, "abc")});
  EXPECT_EQ(unknown.status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(Blobs(), 0);
}

TEST_F(BadUploadTest, SubmittingAnIncompleteUploadIsAFailedPrecondition) {
  grpc::ClientContext context;
  v1::SubmitRequest request;
  *request.mutable_clip()->add_files() = Entry("images/000000.png", "never uploaded");
  v1::Job job;
  const auto status = cluster_.stub().Submit(&context, request, &job);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::FAILED_PRECONDITION);
  EXPECT_NE(status.error_message().find("images/000000.png"), std::string::npos);
}

TEST_F(BadUploadTest, CliReportsTheSizeLimitWithExitCodeEight) {
  // A clip whose frame is 2 MB (zeros: its bytes are the worker's to decode), over the server's 1 MB.
  MakeClip(cluster_.path("big"));
  std::filesystem::resize_file(cluster_.path("big") / "images" / "000003.png", 2000000);
  const auto result = RunCli(cluster_.address(), {"submit", cluster_.path("big").string()});
  EXPECT_EQ(result.exit_code, 8) << result.err;
  EXPECT_NE(result.err.find("RESOURCE_EXHAUSTED"), std::string::npos) << result.err;
  EXPECT_EQ(Partials(), 0);
}

// A clip with a huge file is refused from its sizes, before its files are read: a 50 GB file was
// hashed for a minute and more, then refused without a name (found 2026-12-05). A sparse 50 GB file
// here: reading it whole would take this test minutes.
TEST_F(BadUploadTest, AHugeClipIsRefusedFromItsSizesNamingItsLargestFile) {
  MakeClip(cluster_.path("huge"));
  std::filesystem::resize_file(cluster_.path("huge") / "images" / "000007.png", std::uintmax_t{50} << 30);
  const auto started = std::chrono::steady_clock::now();
  const auto result = RunCli(cluster_.address(), {"submit", cluster_.path("huge").string()});
  EXPECT_EQ(result.exit_code, 8) << result.err;
  EXPECT_NE(result.err.find("its largest file: images/000007.png"), std::string::npos) << result.err;
  EXPECT_LT(std::chrono::steady_clock::now() - started, std::chrono::seconds(30));
  EXPECT_EQ(Partials(), 0);
}

// A clip the worker's loader would refuse is refused by the CLI before its upload, by the same rules
// (common/clip_files.h, common/image_bytes.h): a clip missing a mask was uploaded, queued and failed
// only on a worker (found 2026-12-05).
TEST_F(BadUploadTest, AClipMissingAMaskOrHoldingATruncatedPngIsRefusedBeforeItsUpload) {
  MakeClip(cluster_.path("nomask"));
  std::filesystem::remove(cluster_.path("nomask") / "masks" / "000003.png");
  auto result = RunCli(cluster_.address(), {"submit", cluster_.path("nomask").string()});
  EXPECT_EQ(result.exit_code, 2) << result.err;
  EXPECT_NE(result.err.find("nomask/masks: holds 7 files but poses_bounds.npy has 8 rows"), std::string::npos)
      << result.err;
  EXPECT_NE(result.err.find("no file named 000003.* for images/000003.png"), std::string::npos) << result.err;
  EXPECT_NE(result.err.find("found before the upload: nothing was sent"), std::string::npos) << result.err;

  MakeClip(cluster_.path("cut"));
  const auto frame = cluster_.path("cut") / "images" / "000005.png";
  WriteBytes(frame, ReadBytes(frame).substr(0, 300));
  result = RunCli(cluster_.address(), {"submit", cluster_.path("cut").string()});
  EXPECT_EQ(result.exit_code, 2) << result.err;
  EXPECT_NE(result.err.find("cut/images/000005.png: a truncated PNG"), std::string::npos) << result.err;
  EXPECT_EQ(Blobs(), 0);
  // The ground truth's files too (a damaged gt/depth/*.npy failed the job on a worker).
  MakeClip(cluster_.path("gtcut"));
  const auto truth = cluster_.path("gtcut") / "gt" / "depth" / "000002.npy";
  WriteBytes(truth, ReadBytes(truth).substr(0, 20));
  result = RunCli(cluster_.address(), {"submit", cluster_.path("gtcut").string()});
  EXPECT_EQ(result.exit_code, 2) << result.err;
  EXPECT_NE(result.err.find("gtcut/gt/depth/000002.npy"), std::string::npos) << result.err;
  EXPECT_NE(result.err.find("found before the upload: nothing was sent"), std::string::npos) << result.err;
  EXPECT_EQ(Blobs(), 0);
  // A mask of another size than the frames' (told by its header; found only on a worker before).
  MakeClip(cluster_.path("bigmask"));
  ASSERT_EQ(
      std::system((BuiltBinary("worker/runtime/endorecon-worker") + " synth " +
                   cluster_.path("small").string() + " --frames 2 --width 16 --height 12 > /dev/null 2>&1")
                      .c_str()),
      0);
  std::filesystem::copy_file(cluster_.path("small") / "masks" / "000000.png",
                             cluster_.path("bigmask") / "masks" / "000002.png",
                             std::filesystem::copy_options::overwrite_existing);
  result = RunCli(cluster_.address(), {"submit", cluster_.path("bigmask").string()});
  EXPECT_EQ(result.exit_code, 2) << result.err;
  EXPECT_NE(result.err.find("bigmask/masks/000002.png: size 16x12 differs from the clip's 32x24"),
            std::string::npos)
      << result.err;
  EXPECT_EQ(Blobs(), 0);
  // A NaN in a pose (it failed the job on a worker, after the upload), and a row the loader refuses.
  MakeClip(cluster_.path("nanpose"));
  const auto poses = cluster_.path("nanpose") / "poses_bounds.npy";
  NpyArray rows = ReadNpy(poses);
  rows.data[3 * kPoseColumns + 8] = NAN;
  WriteNpyFloat64(poses, rows.data.data(), rows.shape);
  result = RunCli(cluster_.address(), {"submit", cluster_.path("nanpose").string()});
  EXPECT_EQ(result.exit_code, 2) << result.err;
  EXPECT_NE(result.err.find("nanpose/poses_bounds.npy row 3: column 8 (t[1]) is NaN; every value must be "
                            "finite (found before the upload: nothing was sent)"),
            std::string::npos)
      << result.err;
  EXPECT_EQ(Blobs(), 0);
  // And what the loader's camera checks refuse of a row (common/pose_rows.h): near beyond far.
  rows.data[3 * kPoseColumns + 8] = 0;
  rows.data[2 * kPoseColumns + 15] = rows.data[2 * kPoseColumns + 16] + 1;
  WriteNpyFloat64(poses, rows.data.data(), rows.shape);
  result = RunCli(cluster_.address(), {"submit", cluster_.path("nanpose").string()});
  EXPECT_EQ(result.exit_code, 2) << result.err;
  EXPECT_NE(
      result.err.find("nanpose/poses_bounds.npy row 2: depth bounds must be finite with 0 <= near < far"),
      std::string::npos)
      << result.err;
  EXPECT_NE(result.err.find("(found before the upload: nothing was sent)"), std::string::npos) << result.err;
  EXPECT_EQ(Blobs(), 0);
  EXPECT_EQ(Partials(), 0);
  // What the server refuses of the job itself is found before the upload too (a --send-to this server
  // has no PACS for was refused after it).
  MakeClip(cluster_.path("whole"));
  result = RunCli(cluster_.address(), {"submit", cluster_.path("whole").string(), "--send-to", "pacs9"});
  EXPECT_EQ(result.exit_code, 3) << result.err;
  EXPECT_NE(result.err.find("submit (checked before the upload): no PACS named 'pacs9' is configured on the "
                            "server"),
            std::string::npos)
      << result.err;
  WriteBytes(cluster_.path("typo.json"), R"({"rays_per_batch": 512, "iteration": 300})");
  result = RunCli(cluster_.address(), {"submit", cluster_.path("whole").string(), "--config",
                                       cluster_.path("typo.json").string()});
  EXPECT_EQ(result.exit_code, 2) << result.err;
  EXPECT_NE(result.err.find("options.config_json (--config): "), std::string::npos) << result.err;
  EXPECT_NE(result.err.find("iteration"), std::string::npos) << result.err;
  EXPECT_EQ(Blobs(), 0);
  EXPECT_EQ(Partials(), 0);
  // The same clip whole goes up and is queued: the files its layout names, not what else lies in its
  // folder (a spreadsheet of patients, a 50 GB video beside the frames were uploaded too).
  MakeClip(cluster_.path("whole"));
  WriteBytes(cluster_.path("whole") / "patients.csv", "MRN,name\n12345,Doe^John\n");
  std::filesystem::create_directories(cluster_.path("whole") / "video");
  WriteBytes(cluster_.path("whole") / "video" / "case.mp4", "");
  std::filesystem::resize_file(cluster_.path("whole") / "video" / "case.mp4", std::uintmax_t{50} << 30);
  result = RunCli(cluster_.address(), {"submit", cluster_.path("whole").string()});
  EXPECT_EQ(result.exit_code, 0) << result.err;
  EXPECT_NE(result.err.find("left out 3 file(s) under " + cluster_.path("whole").string() +
                            " that the clip's layout does not name (docs/formats.md), not uploaded: "
                            "patients.csv, synth.json, video/case.mp4"),
            std::string::npos)
      << result.err;
  EXPECT_GT(Blobs(), 0);
  grpc::ClientContext context;
  v1::ListJobsRequest list;
  v1::ListJobsResponse jobs;
  ASSERT_TRUE(cluster_.stub().List(&context, list, &jobs).ok());
  ASSERT_EQ(jobs.jobs_size(), 1);
  std::set<std::string> paths;
  const v1::Job queued = cluster_.Job(jobs.jobs(0).id());
  for (const auto& file : queued.clip().files()) paths.insert(file.path());
  EXPECT_TRUE(paths.count("poses_bounds.npy") && paths.count("images/000000.png") &&
              paths.count("masks/000007.png"));
  EXPECT_FALSE(paths.count("patients.csv") || paths.count("video/case.mp4"));
  // Said with --json too (on stderr; stdout is the job), and names print as text: a file named with a
  // line break and an escape sequence printed a line of its own.
  WriteBytes(cluster_.path("whole") / "evil\nuploaded 0 file(s)\x1b[31m", "");
  result = RunCli(cluster_.address(), {"--json", "submit", cluster_.path("whole").string()});
  EXPECT_EQ(result.exit_code, 0) << result.err;
  EXPECT_NE(result.err.find("left out 4 file(s)"), std::string::npos) << result.err;
  EXPECT_NE(result.err.find("evil?uploaded 0 file(s)?[31m"), std::string::npos) << result.err;
  EXPECT_EQ(result.err.find("\nuploaded 0"), std::string::npos) << result.err;
}

}  // namespace
}  // namespace endorecon::testing
