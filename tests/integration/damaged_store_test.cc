// A stored file the disk damaged (cut short, a flipped bit): the server sent it to every worker,
// which refused it, until the job's attempts ran out; and a submit of the same clip found it
// "already on the server" and was refused, blaming the user's intact file (found by a bad-input
// walk-through, 2026-12-06). Now a damaged copy is set aside when it is found (an upload's query, a
// download), the job it belongs to fails once saying so, and the same submit stores the file anew.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "common/sha256.h"
#include "tests/integration/service_harness.h"

namespace endorecon::testing {
namespace {

namespace fs = std::filesystem;

std::size_t SetAside(const Cluster& cluster) {
  const fs::path damaged = cluster.data_dir() / "damaged";
  if (!fs::exists(damaged)) return 0;
  return static_cast<std::size_t>(std::distance(fs::directory_iterator(damaged), fs::directory_iterator()));
}

TEST(DamagedStoreTest, ADamagedStoredFileIsSetAsideItsJobFailsOnceAndTheSameSubmitStoresItAnew) {
  Cluster cluster;
  const fs::path clip = cluster.path("clip");
  MakeClip(clip);
  const auto blob_of = [&](const std::string& frame) {
    const std::string sha = Sha256File(clip / "images" / frame);
    return cluster.data_dir() / "blobs" / sha.substr(0, 2) / sha;
  };
  const std::string first = cluster.Submit(clip, {"--iterations", "5"});

  // Cut short on the disk: the next submit's query finds it, sets it aside and sends it again.
  ASSERT_TRUE(fs::exists(blob_of("000003.png")));
  fs::resize_file(blob_of("000003.png"), 100);
  CliResult again = RunCli(cluster.address(), {"submit", clip.string(), "--iterations", "5"});
  ASSERT_EQ(again.exit_code, 0) << again.err << cluster.ServerLog();
  EXPECT_EQ(again.err.find(": 0 B sent"), std::string::npos) << "the damaged file is sent again: " << again.err;
  EXPECT_EQ(SetAside(cluster), 1u);
  EXPECT_EQ(fs::file_size(blob_of("000003.png")), fs::file_size(clip / "images" / "000003.png"));
  EXPECT_NE(cluster.ServerLog().find("is damaged: its bytes no longer hash to their digest"), std::string::npos);

  // A flipped bit, the size kept: found as the file is sent to a worker, which never gets it whole.
  {
    std::fstream file(blob_of("000005.png"), std::ios::in | std::ios::out | std::ios::binary);
    file.seekp(60);
    file.put('\x5a');
  }
  cluster.StartWorker("w1");
  const v1::Job failed = cluster.WaitForState(first, v1::FAILED);
  EXPECT_EQ(failed.attempts(), 0) << "the server's fault, found at once: no attempt spent on it";
  EXPECT_NE(failed.error().find("the server's stored copy of 'images/000005.png'"), std::string::npos)
      << failed.error();
  EXPECT_NE(failed.error().find("submit the clip again"), std::string::npos) << failed.error();
  EXPECT_EQ(SetAside(cluster), 2u);

  // The second job names the same content: gone from the store, it fails saying so, not after three
  // attempts; the same submit once more stores the file anew, and its job succeeds.
  const auto queued = again.out.find("job ");
  ASSERT_NE(queued, std::string::npos) << again.out;
  const std::string second = again.out.substr(queued + 4, again.out.find(' ', queued + 4) - queued - 4);
  const v1::Job gone = cluster.WaitForState(second, v1::FAILED);
  EXPECT_EQ(gone.attempts(), 0);
  EXPECT_NE(gone.error().find("no longer in the server's store"), std::string::npos) << gone.error();
  EXPECT_NE(gone.error().find("submit the clip again"), std::string::npos) << gone.error();
  CliResult third = RunCli(cluster.address(), {"submit", clip.string(), "--iterations", "5", "--wait"});
  EXPECT_EQ(third.exit_code, 0) << third.err << cluster.ServerLog();

  // A result damaged: its fetch is refused as DATA_LOSS, and so is the next one (it was NOT_FOUND,
  // exit 3, which a script reads as "no such job").
  const auto at = third.out.find("job ");
  ASSERT_NE(at, std::string::npos) << third.out;
  const std::string done = third.out.substr(at + 4, third.out.find(' ', at + 4) - at - 4);
  std::string metrics_sha;
  const v1::Job finished = cluster.Job(done);
  for (const auto& file : finished.result().files()) {
    if (file.path() == "metrics.json") metrics_sha = file.sha256();
  }
  ASSERT_FALSE(metrics_sha.empty());
  fs::resize_file(cluster.data_dir() / "blobs" / metrics_sha.substr(0, 2) / metrics_sha, 10);
  for (int attempt = 0; attempt < 2; ++attempt) {
    const CliResult fetched = RunCli(cluster.address(), {"fetch", done, "-o", cluster.path("out").string()});
    EXPECT_EQ(fetched.exit_code, 9) << fetched.err;
    EXPECT_NE(fetched.err.find("metrics.json"), std::string::npos) << fetched.err;
  }
}

}  // namespace
}  // namespace endorecon::testing
