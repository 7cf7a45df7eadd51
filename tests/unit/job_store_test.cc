#include "server/job_store.h"

#include <gtest/gtest.h>

#include "common/error.h"
#include "tests/unit/temp_dir.h"

namespace endorecon::server {
namespace {

v1::Job MakeJob(const std::string& id, v1::JobState state, int priority = 0) {
  v1::Job job;
  job.set_id(id);
  job.set_state(state);
  job.set_priority(priority);
  job.set_name(std::string("clip-").append(id));
  job.mutable_options()->set_iterations(30);
  return job;
}

TEST(JobStoreTest, JobsSurviveReopening) {
  testing::TempDir dir("jobstore");
  std::int64_t seq_b = 0;
  {
    JobStore store(dir / "jobs.sqlite");
    store.Insert(MakeJob("a", v1::QUEUED));
    seq_b = store.Insert(MakeJob("b", v1::RUNNING, 5));
    auto b = MakeJob("b", v1::SUCCEEDED, 5);
    b.mutable_result()->add_files()->set_path("metrics.json");
    store.Update(b);
  }
  JobStore reopened(dir / "jobs.sqlite");
  const auto b = reopened.Get("b");
  ASSERT_TRUE(b.has_value());
  EXPECT_EQ(b->seq, seq_b);
  EXPECT_EQ(b->job.state(), v1::SUCCEEDED);
  EXPECT_EQ(b->job.priority(), 5);
  EXPECT_EQ(b->job.result().files(0).path(), "metrics.json");
  EXPECT_EQ(b->job.options().iterations(), 30);
  EXPECT_FALSE(reopened.Get("missing").has_value());
}

TEST(JobStoreTest, UnfinishedListsQueuedAndRunningOldestFirst) {
  testing::TempDir dir("jobstore");
  JobStore store(dir / "jobs.sqlite");
  store.Insert(MakeJob("q1", v1::QUEUED));
  store.Insert(MakeJob("done", v1::SUCCEEDED));
  store.Insert(MakeJob("r1", v1::RUNNING));
  store.Insert(MakeJob("q2", v1::QUEUED));
  const auto unfinished = store.Unfinished();
  ASSERT_EQ(unfinished.size(), 3u);
  EXPECT_EQ(unfinished[0].job.id(), "q1");
  EXPECT_EQ(unfinished[1].job.id(), "r1");
  EXPECT_EQ(unfinished[2].job.id(), "q2");
  const auto counts = store.CountByState();
  EXPECT_EQ(counts.at(v1::QUEUED), 2);
  EXPECT_EQ(counts.at(v1::RUNNING), 1);
  EXPECT_EQ(counts.at(v1::SUCCEEDED), 1);
}

TEST(JobStoreTest, ListPagesNewestFirstWithStateFilter) {
  testing::TempDir dir("jobstore");
  JobStore store(dir / "jobs.sqlite");
  for (int i = 0; i < 7; ++i)
    store.Insert(MakeJob(std::string("j").append(std::to_string(i)), i % 2 ? v1::FAILED : v1::QUEUED));
  const auto first = store.List({}, 3, 0);
  ASSERT_EQ(first.jobs.size(), 3u);
  EXPECT_EQ(first.jobs[0].id(), "j6");
  EXPECT_EQ(first.jobs[2].id(), "j4");
  ASSERT_GT(first.next_before_seq, 0);
  const auto second = store.List({}, 3, first.next_before_seq);
  ASSERT_EQ(second.jobs.size(), 3u);
  EXPECT_EQ(second.jobs[0].id(), "j3");
  const auto last = store.List({}, 3, second.next_before_seq);
  ASSERT_EQ(last.jobs.size(), 1u);
  EXPECT_EQ(last.next_before_seq, 0);
  const auto failed = store.List({v1::FAILED}, 10, 0);
  ASSERT_EQ(failed.jobs.size(), 3u);
  for (const auto& job : failed.jobs) EXPECT_EQ(job.state(), v1::FAILED);
}

TEST(JobStoreTest, UpdatingAnUnknownJobIsNotFound) {
  testing::TempDir dir("jobstore");
  JobStore store(dir / "jobs.sqlite");
  try {
    store.Update(MakeJob("ghost", v1::QUEUED));
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kNotFound);
  }
  EXPECT_TRUE(store.Writable());
}

}  // namespace
}  // namespace endorecon::server
