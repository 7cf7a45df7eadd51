// Retention against a real server: finished jobs' files go after the configured age, their records
// stay marked expired, content that a live job shares stays, and the dry run shows it all first
// without changing anything. Files no job references go --orphan-hours after the server first found them.
#include <gtest/gtest.h>

#include <set>

#include "tests/integration/audit_reader.h"
#include "tests/integration/service_harness.h"

namespace endorecon::testing {
namespace fs = std::filesystem;
namespace {

bool HasBlob(const Cluster& cluster, const std::string& sha256) {
  return fs::exists(cluster.data_dir() / "blobs" / sha256.substr(0, 2) / sha256);
}

TEST(RetentionTest, ExpiresFinishedJobsAndKeepsWhatLiveJobsShare) {
  Cluster cluster;
  MakeClip(cluster.path("shared"), 1);
  MakeClip(cluster.path("alone"), 2);
  const auto old_shared = cluster.Submit(cluster.path("shared"), {});
  const auto live_shared = cluster.Submit(cluster.path("shared"), {});
  const auto old_alone = cluster.Submit(cluster.path("alone"), {});
  for (const auto& id : {old_shared, old_alone})
    ASSERT_EQ(RunCli(cluster.address(), {"cancel", id}).exit_code, 0);
  const auto shared_clip = cluster.Job(live_shared).clip();
  const auto alone_clip = cluster.Job(old_alone).clip();
  // Two synthetic clips may share a file (the same cameras): that one stays with the live job.
  std::set<std::string> shared, only_alone;
  for (const auto& file : shared_clip.files()) shared.insert(file.sha256());
  for (const auto& file : alone_clip.files()) {
    if (!shared.count(file.sha256())) only_alone.insert(file.sha256());
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(1200));

  // 0.00001 days = 0.864 s: both cancelled jobs are old enough.
  TempDir scratch("retention");
  Process dry_run({BuiltBinary("server/endorecon-server"), "retention", "--data-dir",
                   cluster.data_dir().string(), "--retention-days", "0.00001", "--dry-run"},
                  scratch / "dry-run");
  ASSERT_EQ(dry_run.Wait(), 0) << ReadBytes(scratch / "dry-run");
  const auto plan = ReadBytes(scratch / "dry-run");
  EXPECT_NE(plan.find("would expire job " + old_shared), std::string::npos) << plan;
  EXPECT_NE(plan.find("would expire job " + old_alone), std::string::npos) << plan;
  EXPECT_EQ(plan.find(live_shared), std::string::npos) << plan;
  EXPECT_NE(plan.find("2 job(s)"), std::string::npos) << plan;
  EXPECT_NE(plan.find("; " + std::to_string(only_alone.size()) + " blob(s), "), std::string::npos) << plan;
  EXPECT_NE(plan.find("; " + std::to_string(shared.size()) + " blob(s) stay"), std::string::npos) << plan;
  for (const auto& file : alone_clip.files()) EXPECT_TRUE(HasBlob(cluster, file.sha256()));
  EXPECT_EQ(cluster.Job(old_alone).expired_unix_ms(), 0);

  cluster.KillServer(SIGTERM);
  Cluster retaining({"--retention-days", "0.00001", "--retention-check-s", "0.2"}, false);
  fs::remove_all(retaining.data_dir());
  fs::copy(cluster.data_dir(), retaining.data_dir(), fs::copy_options::recursive);
  retaining.StartServer();
  ASSERT_TRUE(
      WaitUntil([&] { return retaining.Job(old_alone).expired_unix_ms() > 0; }, std::chrono::seconds(10)))
      << retaining.ServerLog();
  EXPECT_GT(retaining.Job(old_shared).expired_unix_ms(), 0);
  EXPECT_EQ(retaining.Job(live_shared).expired_unix_ms(), 0);
  EXPECT_EQ(retaining.Job(live_shared).state(), v1::QUEUED);
  for (const auto& digest : only_alone) EXPECT_FALSE(HasBlob(retaining, digest)) << digest;
  for (const auto& file : shared_clip.files()) EXPECT_TRUE(HasBlob(retaining, file.sha256())) << file.path();

  const auto fetched =
      RunCli(retaining.address(), {"fetch", old_alone, "-o", scratch.path().string() + "/out"});
  EXPECT_EQ(fetched.exit_code, 7) << fetched.err;
  EXPECT_NE(fetched.err.find("expired"), std::string::npos) << fetched.err;
  const auto status = RunCli(retaining.address(), {"status", old_alone});
  EXPECT_NE(status.out.find("expired"), std::string::npos) << status.out;
  const auto audit = AuditLines(retaining.data_dir() / "audit.jsonl");
  EXPECT_EQ(AuditFind(audit, "Retention", "EXPIRED", "server", old_alone).size(), 1u);
  EXPECT_EQ(AuditFind(audit, "Retention", "EXPIRED", "server", live_shared).size(), 0u);
}

// A data folder restored with a job store older than its blobs: the files only newer jobs named
// are no job's, and their copies keep their old times. They stay --orphan-hours from when the
// server first found them so (they were deleted 56 ms after the start; found 2026-12-07), and a
// restart does not count those hours anew (with the hours counted from each start, a server
// restarted more often than --orphan-hours never deleted an orphan; found 2026-12-07).
TEST(RetentionTest, FilesNoJobNamesGoTheOrphanHoursAfterTheServerFirstFoundThemRestartsOrNot) {
  Cluster cluster({"--orphan-hours", "0.002", "--retention-check-s", "0.2"});  // 7.2 s
  MakeClip(cluster.path("clip"));
  cluster.Submit(cluster.path("clip"), {});  // a job store that names other files
  const fs::path orphan = cluster.data_dir() / "blobs" / "ab" / ("ab" + std::string(62, 'a'));
  fs::create_directories(orphan.parent_path());
  WriteBytes(orphan, "the result of a job the restored store does not have");
  fs::last_write_time(orphan, fs::file_time_type::clock::now() - std::chrono::hours(72));
  const auto written = std::chrono::steady_clock::now();
  ASSERT_TRUE(WaitUntil(
      [&] {
        return ReadBytes(cluster.data_dir() / "orphans.json")
                   .find("\"blobs/ab/" + orphan.filename().string() + "\"") != std::string::npos;
      },
      std::chrono::seconds(5)))
      << cluster.ServerLog();
  // The dry run counts it as waiting, from the server's orphans.json.
  TempDir scratch("retention");
  Process dry_run({BuiltBinary("server/endorecon-server"), "retention", "--data-dir",
                   cluster.data_dir().string(), "--retention-days", "0", "--orphan-hours", "1", "--dry-run"},
                  scratch / "dry-run");
  ASSERT_EQ(dry_run.Wait(), 0) << ReadBytes(scratch / "dry-run");
  const auto plan = ReadBytes(scratch / "dry-run");
  EXPECT_NE(
      plan.find(
          "0 file(s), 0 bytes, that no job references would be deleted (--orphan-hours 1); 1 more are not "
          "old enough yet"),
      std::string::npos)
      << plan;
  std::this_thread::sleep_until(written + std::chrono::seconds(3));
  EXPECT_TRUE(fs::exists(orphan)) << "deleted before --orphan-hours from when it was first found";
  cluster.KillServer(SIGTERM);
  const auto restarted = std::chrono::steady_clock::now();
  cluster.StartServer();
  EXPECT_TRUE(WaitUntil([&] { return !fs::exists(orphan); }, std::chrono::seconds(15)))
      << cluster.ServerLog();
  const auto gone = std::chrono::steady_clock::now();
  EXPECT_GE(gone - written, std::chrono::milliseconds(7200));
  EXPECT_LT(gone - restarted, std::chrono::milliseconds(6500)) << "the restart counted the hours anew";
}

}  // namespace
}  // namespace endorecon::testing
