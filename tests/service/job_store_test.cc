#include "server/job_store.h"

#include <gtest/gtest.h>
#include <sqlite3.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <thread>
#include <utility>
#include <vector>

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

// A damaged jobs.sqlite started without a word, listed its jobs and failed each job's status as
// "unavailable" (found 2026-12-05): it is refused at start, naming the file; so is one that is no
// database at all.
TEST(JobStoreTest, ADamagedStoreIsRefusedAtStartNamingTheFile) {
  testing::TempDir dir("jobstore");
  {
    JobStore store(dir / "jobs.sqlite");
    for (int i = 0; i < 300; ++i) store.Insert(MakeJob("job-" + std::to_string(i), v1::SUCCEEDED));
  }
  ASSERT_GT(std::filesystem::file_size(dir / "jobs.sqlite"), 16384u);
  // A page of noise anywhere: past the schema (quick_check finds it), or in the schema's own pages,
  // which failed the first statement as "UNAVAILABLE: job store: step: database disk image is
  // malformed", without the file (found 2026-12-05).
  const std::string whole = testing::ReadBytes(dir / "jobs.sqlite");
  for (const std::streamoff at : {std::streamoff{8192}, std::streamoff{4096}, std::streamoff{100}}) {
    testing::WriteBytes(dir / "jobs.sqlite", whole);
    {
      std::fstream file(dir / "jobs.sqlite", std::ios::in | std::ios::out | std::ios::binary);
      file.seekp(at);
      const std::string noise(4096 - std::size_t(at % 4096), '\x5a');
      file.write(noise.data(), std::streamsize(noise.size()));
    }
    try {
      JobStore damaged(dir / "jobs.sqlite");
      ADD_FAILURE() << "a store damaged at byte " << at << " was opened";
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), ErrorCode::kDataLoss) << at << ": " << e.what();
      EXPECT_NE(std::string(e.what()).find((dir / "jobs.sqlite").string()), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("restore it from a backup"), std::string::npos) << e.what();
    }
  }
  testing::WriteBytes(dir / "other.sqlite", std::string(20000, 'x'));
  try {
    JobStore other(dir / "other.sqlite");
    ADD_FAILURE() << "a file that is no database was opened";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kDataLoss) << e.what();
    EXPECT_NE(std::string(e.what()).find("other.sqlite"), std::string::npos) << e.what();
  }
}

TEST(JobStoreTest, StagedWritesAreSeenByGetAtOnceAndReachTheDiskAndPagesOnlyWithFlush) {
  testing::TempDir dir("jobstore");
  JobStore store(dir / "jobs.sqlite");
  const auto seq = store.Insert(MakeJob("a", v1::QUEUED));
  store.Update(MakeJob("a", v1::RUNNING));
  ASSERT_TRUE(store.Get("a").has_value());
  EXPECT_EQ(store.Get("a")->job.state(), v1::RUNNING);
  EXPECT_EQ(store.Get("a")->seq, seq);
  EXPECT_TRUE(store.List({}, 10, 0).jobs.empty()) << "a page shows what is committed";
  {
    // Another process opening the file now (a server restarted after a kill -9) finds nothing.
    JobStore other(dir / "jobs.sqlite");
    EXPECT_FALSE(other.Get("a").has_value());
  }
  store.Flush();
  ASSERT_EQ(store.List({}, 10, 0).jobs.size(), 1u);
  JobStore other(dir / "jobs.sqlite");
  ASSERT_TRUE(other.Get("a").has_value());
  EXPECT_EQ(other.Get("a")->job.state(), v1::RUNNING);
  EXPECT_EQ(other.Get("a")->seq, seq);
}

TEST(JobStoreTest, EachCommitIsReportedWithItsDurationAndItsWrites) {
  testing::TempDir dir("jobstore");
  JobStore store(dir / "jobs.sqlite");
  std::vector<std::pair<double, std::size_t>> commits;
  store.SetCommitObserver([&](double seconds, std::size_t writes) { commits.emplace_back(seconds, writes); });
  store.Flush();
  EXPECT_TRUE(commits.empty()) << "nothing staged, nothing committed";
  store.Insert(MakeJob("a", v1::QUEUED));
  store.Insert(MakeJob("b", v1::QUEUED));
  store.Update(MakeJob("a", v1::RUNNING));  // one row write for a's two
  store.Flush();
  ASSERT_EQ(commits.size(), 1u);
  EXPECT_EQ(commits[0].second, 2u);
  EXPECT_GT(commits[0].first, 0.0);
  EXPECT_LT(commits[0].first, 60.0);
  store.Update(MakeJob("b", v1::RUNNING));
  store.Flush();
  ASSERT_EQ(commits.size(), 2u);
  EXPECT_EQ(commits[1].second, 1u);
}

TEST(JobStoreTest, ManyThreadsWritingAndFlushingAtOnceAllReachTheDiskInOrder) {
  testing::TempDir dir("jobstore");
  constexpr int kThreads = 16, kJobsEach = 25;
  {
    JobStore store(dir / "jobs.sqlite");
    std::vector<std::thread> threads;
    for (int t = 0; t < kThreads; ++t) {
      threads.emplace_back([&store, t] {
        for (int j = 0; j < kJobsEach; ++j) {
          const auto id = std::string("t").append(std::to_string(t)).append("-").append(std::to_string(j));
          store.Insert(MakeJob(id, v1::QUEUED));
          store.Flush();
          store.Update(MakeJob(id, v1::SUCCEEDED));
          store.Flush();
        }
      });
    }
    for (auto& thread : threads) thread.join();
    // A kill -9 now loses nothing: read through a second store without the first's destructor.
    JobStore other(dir / "jobs.sqlite");
    EXPECT_EQ(other.CountByState()[v1::SUCCEEDED], kThreads * kJobsEach);
    EXPECT_EQ(other.CountByState().count(v1::QUEUED), 0u);
  }
  JobStore store(dir / "jobs.sqlite");
  const auto seq = store.Insert(MakeJob("later", v1::QUEUED));
  EXPECT_GT(seq, kThreads * kJobsEach) << "a new job never takes an old seq";
}

TEST(JobStoreTest, ACommitTheDatabaseRefusesBreaksTheStoreAndKeepsNothingOfItsBatch) {
  testing::TempDir dir("jobstore");
  JobStore store(dir / "jobs.sqlite");
  store.Insert(MakeJob("kept", v1::QUEUED));
  store.Flush();
  {
    // Stands in for a disk that refuses the write: the database itself refuses one row.
    sqlite3* db = nullptr;
    ASSERT_EQ(sqlite3_open((dir / "jobs.sqlite").c_str(), &db), SQLITE_OK);
    ASSERT_EQ(sqlite3_exec(db,
                           "CREATE TRIGGER refuse BEFORE INSERT ON jobs WHEN NEW.id = 'poison' "
                           "BEGIN SELECT RAISE(ABORT, 'refused by the test'); END",
                           nullptr, nullptr, nullptr),
              SQLITE_OK);
    sqlite3_close(db);
  }
  store.Insert(MakeJob("innocent", v1::QUEUED));
  store.Update(MakeJob("kept", v1::RUNNING));
  store.Insert(MakeJob("poison", v1::QUEUED));
  try {
    store.Flush();
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kUnavailable);
    EXPECT_NE(std::string(e.what()).find("jobs.sqlite"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("refused by the test"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("must restart"), std::string::npos) << e.what();
  }
  EXPECT_TRUE(store.Broken());
  EXPECT_FALSE(store.Writable());
  EXPECT_THROW(store.Update(MakeJob("kept", v1::FAILED)), Error);
  EXPECT_THROW(store.Flush(), Error);
  JobStore reopened(dir / "jobs.sqlite");
  EXPECT_FALSE(reopened.Get("innocent").has_value()) << "the whole batch was rolled back";
  ASSERT_TRUE(reopened.Get("kept").has_value());
  EXPECT_EQ(reopened.Get("kept")->job.state(), v1::QUEUED);
  EXPECT_FALSE(reopened.Broken());
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
  store.Flush();
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

TEST(JobStoreTest, TenantsSeeTheirOwnJobsAndUsage) {
  testing::TempDir dir("jobstore");
  JobStore store(dir / "jobs.sqlite");
  auto job = [](const std::string& id, v1::JobState state, const std::string& tenant,
                std::int64_t clip_bytes) {
    auto made = MakeJob(id, state);
    made.set_tenant(tenant);
    made.mutable_clip()->add_files()->set_size(clip_bytes);
    return made;
  };
  store.Insert(job("a1", v1::QUEUED, "a", 100));
  store.Insert(job("a2", v1::SUCCEEDED, "a", 50));
  store.Insert(job("b1", v1::RUNNING, "b", 7));
  auto a3 = job("a3", v1::RUNNING, "a", 10);
  store.Insert(a3);
  a3.mutable_checkpoint()->set_size(5);
  store.Update(a3);
  const auto usage = store.UsageOf("a");
  EXPECT_EQ(usage.active_jobs, 2);
  EXPECT_EQ(usage.bytes, 165);
  a3.set_state(v1::SUCCEEDED);
  a3.set_expired_unix_ms(1);
  store.Update(a3);
  EXPECT_EQ(store.UsageOf("a").bytes, 150);
  EXPECT_EQ(store.UsageOf("a").active_jobs, 1);
  EXPECT_EQ(store.UsageOf("nobody").bytes, 0);
  EXPECT_EQ(store.List({}, 10, 0, std::string("b")).jobs.size(), 1u);
  EXPECT_EQ(store.List({}, 10, 0, std::string("a")).jobs.size(), 3u);
  EXPECT_EQ(store.List({}, 10, 0).jobs.size(), 4u);
}

TEST(JobStoreTest, StoresFromBeforeTenantsGainTheColumns) {
  testing::TempDir dir("jobstore");
  {
    sqlite3* db = nullptr;
    ASSERT_EQ(sqlite3_open((dir / "jobs.sqlite").c_str(), &db), SQLITE_OK);
    auto old = MakeJob("old", v1::SUCCEEDED);
    old.mutable_clip()->add_files()->set_size(42);
    const std::string bytes = old.SerializeAsString();
    sqlite3_exec(db,
                 "CREATE TABLE jobs (seq INTEGER PRIMARY KEY AUTOINCREMENT, id TEXT NOT NULL UNIQUE, state "
                 "INTEGER NOT "
                 "NULL, priority INTEGER NOT NULL, job BLOB NOT NULL)",
                 nullptr, nullptr, nullptr);
    sqlite3_stmt* insert = nullptr;
    sqlite3_prepare_v2(db, "INSERT INTO jobs(id, state, priority, job) VALUES('old', 3, 0, ?)", -1, &insert,
                       nullptr);
    sqlite3_bind_blob(insert, 1, bytes.data(), static_cast<int>(bytes.size()), SQLITE_TRANSIENT);
    ASSERT_EQ(sqlite3_step(insert), SQLITE_DONE);
    sqlite3_finalize(insert);
    sqlite3_close(db);
  }
  JobStore store(dir / "jobs.sqlite");
  EXPECT_EQ(store.UsageOf("").bytes, 42);
  EXPECT_TRUE(store.Get("old").has_value());
}

}  // namespace
}  // namespace endorecon::server
