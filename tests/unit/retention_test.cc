#include "server/retention.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

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

}  // namespace
}  // namespace endorecon::server
