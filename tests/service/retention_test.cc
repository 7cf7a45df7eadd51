#include "server/retention.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <set>

#include "server/orphan_watch.h"
#include "tests/unit/temp_dir.h"

namespace endorecon::server {
namespace {

v1::Job JobWith(const std::string& id, v1::JobState state, std::int64_t finished,
                const std::vector<std::string>& clip, const std::string& checkpoint = "") {
  v1::Job job;
  job.set_id(id);
  job.set_state(state);
  job.set_finished_unix_ms(finished);
  for (std::size_t i = 0; i < clip.size(); ++i) {
    auto* file = job.mutable_clip()->add_files();
    file->set_path(fmt::format("f{}", i));
    file->set_sha256(clip[i]);
    file->set_size(3);
  }
  if (!checkpoint.empty()) job.mutable_checkpoint()->set_sha256(checkpoint);
  return job;
}

TEST(RetentionTest, PlansOnlyBlobsNoLiveOrRecentJobShares) {
  testing::TempDir dir("retention");
  JobStore store(dir / "jobs.sqlite");
  BlobStore blobs(dir.path());
  const auto a = blobs.Put("aaa"), b = blobs.Put("bbb"), c = blobs.Put("ccc"), d = blobs.Put("ddd");
  store.Insert(JobWith("old", v1::SUCCEEDED, 100, {a, b}));
  store.Insert(JobWith("old-cancelled", v1::CANCELLED, 100, {c}));
  store.Insert(JobWith("live", v1::RUNNING, 0, {b}, c));  // shares b, and c as its checkpoint
  store.Insert(JobWith("recent", v1::FAILED, 900, {d}));
  auto expired = JobWith("expired", v1::SUCCEEDED, 50, {a});
  expired.set_expired_unix_ms(60);
  store.Insert(expired);

  const auto plan = PlanRetention(store, blobs, 500);
  ASSERT_EQ(plan.jobs.size(), 2u);
  EXPECT_EQ(plan.jobs[0].id(), "old");
  EXPECT_EQ(plan.jobs[1].id(), "old-cancelled");
  EXPECT_EQ(plan.blobs, std::vector<std::string>{a});
  EXPECT_EQ(plan.bytes, 3);
  EXPECT_EQ(plan.kept_shared, 2);
  EXPECT_TRUE(blobs.Has(a));  // planning deletes nothing
  EXPECT_EQ(PlanRetention(store, blobs, 1000).jobs.size(), 3u);
}

TEST(RetentionTest, KeepsAJobWhoseDicomResultsAreStillBeingSent) {
  testing::TempDir dir("retention");
  JobStore store(dir / "jobs.sqlite");
  BlobStore blobs(dir.path());
  const auto a = blobs.Put("aaa"), b = blobs.Put("bbb"), c = blobs.Put("ccc");
  const auto with_send = [](v1::Job job, v1::DicomSend::State state) {
    auto* send = job.add_sends();
    send->set_destination("pacs1");
    send->set_state(state);
    return job;
  };
  store.Insert(with_send(JobWith("pending", v1::SUCCEEDED, 100, {a}), v1::DicomSend::PENDING));
  store.Insert(with_send(JobWith("sending", v1::SUCCEEDED, 100, {b}), v1::DicomSend::SENDING));
  store.Insert(with_send(JobWith("failed", v1::SUCCEEDED, 100, {c}), v1::DicomSend::SEND_FAILED));

  const auto plan = PlanRetention(store, blobs, 500);
  ASSERT_EQ(plan.jobs.size(), 1u);
  EXPECT_EQ(plan.jobs[0].id(), "failed");  // a failed send waits for a person, not for retention
  EXPECT_EQ(plan.blobs, std::vector<std::string>{c});
}

// A running job's earlier checkpoints, an upload never submitted and a partial upload given up were
// kept for good: retention looked only at the files of expiring jobs (found 2026-12-05).
TEST(RetentionTest, FilesNoJobReferencesGoOnceOldEnough) {
  testing::TempDir dir("retention");
  JobStore store(dir / "jobs.sqlite");
  BlobStore blobs(dir.path());
  const auto clip = blobs.Put("clip"), checkpoint = blobs.Put("checkpoint 2"),
             earlier = blobs.Put("checkpoint 1"), fresh = blobs.Put("uploaded a minute ago");
  store.Insert(JobWith("live", v1::RUNNING, 0, {clip}, checkpoint));
  const std::string partial_sha(64, 'e');
  testing::WriteBytes(dir / "partial" / (partial_sha + ".part"), "half an upl");
  // Another tenant's upload of the live job's clip (proof of possession, BlobHolders), given up: the
  // clip is stored whole, so the partial goes too.
  const auto proof = dir / "partial" / (clip + ".oncology.part");
  testing::WriteBytes(proof, "cl");
  const auto two_days_ago = std::filesystem::file_time_type::clock::now() - std::chrono::hours(48);
  for (const auto& sha : {clip, checkpoint, earlier})
    std::filesystem::last_write_time(blobs.PathOf(sha), two_days_ago);
  std::filesystem::last_write_time(dir / "partial" / (partial_sha + ".part"), two_days_ago);
  std::filesystem::last_write_time(proof, two_days_ago);

  auto plan = PlanRetention(store, blobs, kKeepJobs, blobs.Files());
  EXPECT_TRUE(plan.jobs.empty());
  EXPECT_EQ(plan.orphans.size(), 4u) << "the fresh upload is no job's too";
  // Found so long ago, as the server's OrphanWatch would have: old enough by their last write alone.
  OrphanWatch().Sift(plan,
                     {std::filesystem::file_time_type::clock::now() - std::chrono::hours(24),
                      std::numeric_limits<std::int64_t>::max()},
                     0);
  EXPECT_EQ(plan.orphans_waiting, 1);
  ASSERT_EQ(plan.orphans.size(), 3u);
  std::set<std::string> orphans;
  for (const auto& file : plan.orphans)
    orphans.insert(file.sha256 + (file.owner.empty() ? "" : "." + file.owner) +
                   (file.partial ? ".part" : ""));
  EXPECT_EQ(orphans, (std::set<std::string>{earlier, partial_sha + ".part", clip + ".oncology.part"}));
  EXPECT_EQ(plan.orphan_bytes, 12 + 11 + 2);
  EXPECT_TRUE(PlanRetention(store, blobs, kKeepJobs).orphans.empty()) << "no cutoff, no orphans";

  for (const auto& file : plan.orphans) blobs.Remove(file);
  EXPECT_FALSE(blobs.Has(earlier));
  EXPECT_FALSE(std::filesystem::exists(dir / "partial" / (partial_sha + ".part")));
  EXPECT_FALSE(std::filesystem::exists(proof));
  for (const auto& sha : {clip, checkpoint, fresh}) EXPECT_TRUE(blobs.Has(sha));
}

}  // namespace
}  // namespace endorecon::server
