// The job state machine on its own, with a clock the test moves: every transition of
// server/job_coordinator.h's diagram, lease expiry, attempt counting and the races of a cancel
// with a worker's report, failure, completion and vanishing.
#include "server/job_coordinator.h"

#include <gtest/gtest.h>

#include <atomic>
#include <functional>
#include <limits>
#include <optional>
#include <set>
#include <string>
#include <thread>

#include "common/error.h"
#include "common/sha256.h"
#include "server/pacs_directory.h"
#include "tests/unit/clip_fixture.h"
#include "tests/unit/temp_dir.h"

namespace endorecon::server {
namespace {

using std::chrono::seconds;

constexpr auto kTtl = seconds(30);

// The code of the Error `call` throws; nullopt when it throws none.
std::optional<ErrorCode> CodeOf(const std::function<void()>& call) {
  try {
    call();
  } catch (const Error& e) {
    return e.code();
  }
  return std::nullopt;
}

class JobCoordinatorTest : public ::testing::Test {
 protected:
  JobCoordinatorTest()
      : store_(dir_ / "jobs.sqlite"),
        blobs_(dir_ / "blobs"),
        leases_(kTtl),
        workers_(kTtl),
        metrics_(""),
        coordinator_({store_, blobs_, scheduler_, leases_, workers_, hub_, metrics_}, 2, {},
                     [this] { return now_; }) {}

  // A manifest of one file with these bytes, uploaded by `tenant` (BlobHolders: it holds them) to
  // `coordinator` (the fixture's by default).
  v1::Manifest Uploaded(const std::string& path, const std::string& bytes, const std::string& tenant = "",
                        JobCoordinator* coordinator = nullptr) {
    v1::Manifest manifest;
    auto* file = manifest.add_files();
    file->set_path(path);
    file->set_size(static_cast<std::int64_t>(bytes.size()));
    file->set_sha256(blobs_.Put(bytes));
    (coordinator ? *coordinator : coordinator_)
        .ClientUploadOwner(Principal{tenant + "-client", Role::kClient, tenant, false})
        .proven(file->sha256());
    return manifest;
  }

  std::string Submit() {
    v1::SubmitRequest request;
    *request.mutable_clip() = Uploaded("images/000000.png", "frame of job " + std::to_string(++submitted_));
    return coordinator_.Submit(request, AnonymousPrincipal()).id();
  }

  // The next queued job for `worker` (no waiting).
  std::optional<JobCoordinator::Granted> LeaseNext(const std::string& worker = "worker-1") {
    return coordinator_.Lease(worker, Clock::now());
  }

  v1::Job Get(const std::string& id) { return coordinator_.Get(id, AnonymousPrincipal()); }

  v1::ProgressReply::Action Report(const std::string& lease_id) {
    v1::ProgressUpdate update;
    update.set_lease_id(lease_id);
    update.mutable_progress()->set_iteration(1);
    return coordinator_.Report(update);
  }

  v1::Job Complete(const std::string& lease_id, const v1::Manifest& result) {
    v1::CompleteRequest request;
    request.set_lease_id(lease_id);
    *request.mutable_result() = result;
    return coordinator_.Complete(request);
  }

  v1::Job Fail(const std::string& lease_id, bool retry, bool release = false) {
    v1::FailRequest request;
    request.set_lease_id(lease_id);
    request.set_reason("out of memory");
    request.set_retry(retry);
    request.set_release(release);
    return coordinator_.Fail(request);
  }

  // Moves the clock and takes back what expired.
  void Advance(Clock::duration by) {
    now_ += by;
    coordinator_.ExpireLeases(now_);
  }

  testing::TempDir dir_{"coordinator"};
  JobStore store_;
  BlobStore blobs_;
  Scheduler scheduler_;
  LeaseTable leases_;
  WorkerRegistry workers_;
  WatchHub hub_;
  Metrics metrics_;
  Clock::time_point now_ = Clock::now();
  JobCoordinator coordinator_;
  int submitted_ = 0;
};

TEST_F(JobCoordinatorTest, AJobIsQueuedLeasedAndCompleted) {
  const std::string id = Submit();
  EXPECT_EQ(Get(id).state(), v1::QUEUED);
  const auto granted = LeaseNext();
  ASSERT_TRUE(granted.has_value());
  EXPECT_EQ(granted->job.id(), id);
  EXPECT_EQ(granted->attempt, 1);
  EXPECT_EQ(Get(id).state(), v1::RUNNING);
  EXPECT_EQ(Get(id).worker_id(), "worker-1");
  EXPECT_FALSE(LeaseNext("worker-2").has_value()) << "a running job is leased once";
  EXPECT_EQ(Report(granted->lease_id), v1::ProgressReply::CONTINUE);

  const v1::Job done = Complete(granted->lease_id, Uploaded("metrics.json", "{}"));
  EXPECT_EQ(done.state(), v1::SUCCEEDED);
  EXPECT_EQ(Get(id).result().files(0).path(), "metrics.json");
  EXPECT_TRUE(Get(id).lease_id().empty());
  EXPECT_EQ(CodeOf([&] { coordinator_.CheckLease(granted->lease_id); }), ErrorCode::kFailedPrecondition);
  EXPECT_EQ(Report(granted->lease_id), v1::ProgressReply::STOP_LEASE_LOST);
  EXPECT_EQ(CodeOf([&] { coordinator_.Cancel(id, AnonymousPrincipal()); }), ErrorCode::kFailedPrecondition);
}

// Found by reading the code (2026-12-05): a clip's file declared smaller than its content was
// counted so against the tenant's quota; a name or priority of any size was taken as given.
TEST_F(JobCoordinatorTest, WhatAClientNamesIsBoundedAndSizesAreTheContents) {
  v1::SubmitRequest request;
  *request.mutable_clip() = Uploaded("images/000000.png", std::string(5000, 'x'));
  request.mutable_clip()->mutable_files(0)->set_size(1);
  std::string message = testing::ErrorFrom([&] { coordinator_.Submit(request, AnonymousPrincipal()); });
  EXPECT_NE(message.find("'images/000000.png' of the clip is declared 1 bytes, but its content"),
            std::string::npos)
      << message;
  request.mutable_clip()->mutable_files(0)->set_size(5000);
  request.set_priority(std::numeric_limits<std::int32_t>::min());
  message = testing::ErrorFrom([&] { coordinator_.Submit(request, AnonymousPrincipal()); });
  EXPECT_NE(message.find("priority is -2147483648; expected -100 to 100"), std::string::npos) << message;
  request.set_priority(100);
  request.set_name(std::string(257, 'n'));
  message = testing::ErrorFrom([&] { coordinator_.Submit(request, AnonymousPrincipal()); });
  EXPECT_NE(message.find("name has 257 bytes; at most 256"), std::string::npos) << message;
  request.set_name("clip\x1b[2J");
  message = testing::ErrorFrom([&] { coordinator_.Submit(request, AnonymousPrincipal()); });
  EXPECT_NE(message.find("control character (byte 27)"), std::string::npos) << message;
  request.set_name("clip");
  request.mutable_options()->set_config_json("{\"x\":\"" + std::string(70000, 'y') + "\"}");
  message = testing::ErrorFrom([&] { coordinator_.Submit(request, AnonymousPrincipal()); });
  EXPECT_NE(message.find("options.config_json has 70008 bytes; at most 65536"), std::string::npos) << message;
  request.mutable_options()->clear_config_json();
  request.mutable_options()->set_time_budget_s(0.001);  // a unit slip: 0 (none) or >= 10 s
  message = testing::ErrorFrom([&] { coordinator_.Submit(request, AnonymousPrincipal()); });
  EXPECT_NE(message.find("options.time_budget_s is 0.001000; expected 0 (no budget) or 10 to 604800 seconds"),
            std::string::npos)
      << message;
  request.mutable_options()->set_time_budget_s(1e300);  // without end
  message = testing::ErrorFrom([&] { coordinator_.Submit(request, AnonymousPrincipal()); });
  EXPECT_NE(message.find("expected 0 (no budget) or 10 to 604800 seconds (a week)"), std::string::npos)
      << message;
  request.mutable_options()->set_time_budget_s(0);
  std::int64_t stored = 0;
  for (const auto& [state, count] : store_.CountByState()) stored += count;
  EXPECT_EQ(stored, 0) << "nothing refused was stored";
  request.mutable_options()->clear_config_json();
  EXPECT_EQ(coordinator_.Submit(request, AnonymousPrincipal()).priority(), 100);
}

// A preview's kind names the client's file of it: a worker's `../x` was passed on as given.
TEST_F(JobCoordinatorTest, APreviewOfAnUnknownKindIsDropped) {
  const std::string id = Submit();
  const auto granted = LeaseNext();
  ASSERT_TRUE(granted.has_value());
  for (const char* kind : {"../../home/u/.bashrc", "rgb"}) {
    v1::ProgressUpdate update;
    update.set_lease_id(granted->lease_id);
    update.mutable_preview()->set_kind(kind);
    update.mutable_preview()->set_png("png");
    EXPECT_EQ(coordinator_.Report(update), v1::ProgressReply::CONTINUE);
  }
  const auto changes = hub_.Wait(id, 0, Clock::now() + seconds(1));
  ASSERT_EQ(changes.previews.size(), 1u);
  EXPECT_EQ(changes.previews[0].kind(), "rgb");
}

TEST_F(JobCoordinatorTest, AResultFileNotUploadedKeepsTheJobRunning) {
  const std::string id = Submit();
  const auto granted = LeaseNext();
  ASSERT_TRUE(granted.has_value());
  v1::Manifest result;
  auto* file = result.add_files();
  file->set_path("metrics.json");
  file->set_size(2);
  file->set_sha256(std::string(64, 'a'));
  EXPECT_EQ(CodeOf([&] { Complete(granted->lease_id, result); }), ErrorCode::kFailedPrecondition);
  EXPECT_EQ(Get(id).state(), v1::RUNNING);
}

TEST_F(JobCoordinatorTest, ReportsKeepTheLeaseAndSilenceExpiresIt) {
  const std::string id = Submit();
  EXPECT_EQ(Get(id).first_started_unix_ms(), 0);
  const auto granted = LeaseNext();
  ASSERT_TRUE(granted.has_value());
  const std::int64_t first_start = Get(id).first_started_unix_ms();
  EXPECT_GT(first_start, 0);
  EXPECT_EQ(Get(id).started_unix_ms(), first_start);
  Advance(kTtl - seconds(5));
  EXPECT_EQ(Report(granted->lease_id), v1::ProgressReply::CONTINUE);
  Advance(seconds(10));  // past the first expiry, not the renewed one
  EXPECT_EQ(Get(id).state(), v1::RUNNING);

  Advance(kTtl);
  const v1::Job requeued = Get(id);
  EXPECT_EQ(requeued.state(), v1::QUEUED);
  EXPECT_EQ(requeued.attempts(), 1);
  EXPECT_NE(requeued.error().find("lease expired"), std::string::npos) << requeued.error();
  // The vanished worker comes back: its lease is gone, whatever it sends.
  EXPECT_EQ(Report(granted->lease_id), v1::ProgressReply::STOP_LEASE_LOST);
  EXPECT_EQ(CodeOf([&] { Complete(granted->lease_id, Uploaded("metrics.json", "{}")); }),
            ErrorCode::kFailedPrecondition);
  std::this_thread::sleep_for(std::chrono::milliseconds(2));  // the start times are the wall clock's
  const auto again = LeaseNext("worker-2");
  ASSERT_TRUE(again.has_value());
  EXPECT_EQ(again->attempt, 2);
  EXPECT_EQ(Get(id).first_started_unix_ms(), first_start) << "the first lease's start is kept";
  EXPECT_GT(Get(id).started_unix_ms(), first_start);
}

// A worker that stops while the server is down (a batch allocation's time limit) cannot hand its job
// back, and the lease the restarted server re-grants then expires: that cost an attempt, and a few
// outages failed jobs outright (found 2026-12-07). A worker that calls after the restart and then
// goes silent is lost as usual.
TEST_F(JobCoordinatorTest, ALeaseWhoseWorkerNeverCalledAfterARestartCostsNoAttempt) {
  const std::string id = Submit();
  ASSERT_TRUE(LeaseNext().has_value());
  // A server restarted on the same store: its own queue, leases and workers, rebuilt by Recover.
  struct Restarted {
    Restarted(JobStore& store, BlobStore& blobs, WatchHub& hub, Metrics& metrics,
              const Clock::time_point& now)
        : coordinator({store, blobs, scheduler, leases, workers, hub, metrics}, 2, {},
                      [&now] { return now; }) {
      coordinator.Recover();
    }
    Scheduler scheduler;
    LeaseTable leases{kTtl};
    WorkerRegistry workers{kTtl};
    JobCoordinator coordinator;
  };
  Restarted first(store_, blobs_, hub_, metrics_, now_);
  EXPECT_EQ(first.coordinator.Get(id, AnonymousPrincipal()).state(), v1::RUNNING);
  now_ += kTtl + seconds(1);
  first.coordinator.ExpireLeases(now_);
  const auto requeued = first.coordinator.Get(id, AnonymousPrincipal());
  EXPECT_EQ(requeued.state(), v1::QUEUED);
  EXPECT_EQ(requeued.attempts(), 0);
  EXPECT_NE(requeued.error().find("did not call after the server restarted"), std::string::npos)
      << requeued.error();

  const auto granted = first.coordinator.Lease("worker-1", Clock::now());
  ASSERT_TRUE(granted.has_value());
  Restarted second(store_, blobs_, hub_, metrics_, now_);
  v1::ProgressUpdate update;
  update.set_lease_id(granted->lease_id);
  update.mutable_progress()->set_iteration(1);
  EXPECT_EQ(second.coordinator.Report(update), v1::ProgressReply::CONTINUE);
  now_ += kTtl + seconds(1);
  second.coordinator.ExpireLeases(now_);
  const auto lost = second.coordinator.Get(id, AnonymousPrincipal());
  EXPECT_EQ(lost.state(), v1::QUEUED);
  EXPECT_EQ(lost.attempts(), 1) << "it called after the restart, then went silent";
  EXPECT_NE(lost.error().find("stopped reporting"), std::string::npos) << lost.error();
}

// A worker whose token expired mid-job cannot renew its lease (every call is refused): the job
// went back to the queue with an attempt counted, and a second such loss failed a job that had
// nothing wrong with it (found 2026-12-06). The token a lease notes is the last one its worker's
// calls carried: one replaced in time (a rotation) leaves a lost lease counted as usual.
TEST_F(JobCoordinatorTest, ALeaseLostToItsWorkersExpiredTokenCostsNoAttempt) {
  const std::string id = Submit();  // max_attempts 2
  const std::int64_t expired = NowUnixMs() - 1000;
  for (int loss = 0; loss < 3; ++loss) {
    const auto granted =
        coordinator_.Lease("node-7", Clock::now(), std::nullopt, {}, {"node-7-token", expired});
    ASSERT_TRUE(granted.has_value()) << loss;
    EXPECT_EQ(granted->attempt, 1);
    Advance(kTtl + seconds(1));
    const v1::Job requeued = Get(id);
    ASSERT_EQ(requeued.state(), v1::QUEUED) << requeued.error();
    EXPECT_EQ(requeued.attempts(), 0);
    EXPECT_NE(
        requeued.error().find("worker node-7's token 'node-7-token' expired at " + UtcText(expired) +
                              ", so its calls were refused and its lease expired (not counted as an attempt"),
        std::string::npos)
        << requeued.error();
  }
  // Rotated in time: the lease notes the new token from the worker's next report.
  const auto granted =
      coordinator_.Lease("node-7", Clock::now(), std::nullopt, {}, {"node-7-token", expired});
  ASSERT_TRUE(granted.has_value());
  v1::ProgressUpdate update;
  update.set_lease_id(granted->lease_id);
  EXPECT_EQ(coordinator_.Report(update, {"node-7-token-2", NowUnixMs() + 3600 * 1000}),
            v1::ProgressReply::CONTINUE);
  Advance(kTtl + seconds(1));
  EXPECT_EQ(Get(id).attempts(), 1);
  EXPECT_NE(Get(id).error().find("worker node-7 stopped reporting; its lease expired"), std::string::npos)
      << Get(id).error();
  // A revoked token costs an attempt (revoking is a judgement on the node), and the reason names it.
  coordinator_.SetTokenRevokedAt([](const std::string& name) -> std::int64_t {
    return name == "node-7-token-3" ? 1796540400000 : 0;  // 2026-12-06 07:00:00 UTC
  });
  ASSERT_TRUE(
      coordinator_.Lease("node-7", Clock::now(), std::nullopt, {}, {"node-7-token-3", 0}).has_value());
  Advance(kTtl + seconds(1));
  EXPECT_EQ(Get(id).state(), v1::FAILED) << "its second attempt";
  EXPECT_NE(
      Get(id).error().find("last: worker node-7's token 'node-7-token-3' was revoked at 2026-12-06 07:00:00 "
                           "UTC, so its calls were refused and its lease expired"),
      std::string::npos)
      << Get(id).error();
}

TEST_F(JobCoordinatorTest, TheJobFailsWhenItsAttemptsAreUsedUp) {
  const std::string id = Submit();  // max_attempts 2
  ASSERT_TRUE(LeaseNext().has_value());
  Advance(kTtl + seconds(1));
  EXPECT_EQ(Get(id).state(), v1::QUEUED);
  ASSERT_TRUE(LeaseNext().has_value());
  Advance(kTtl + seconds(1));
  const v1::Job failed = Get(id);
  EXPECT_EQ(failed.state(), v1::FAILED);
  EXPECT_EQ(failed.attempts(), 2);
  EXPECT_NE(failed.error().find("gave up after 2 attempt(s)"), std::string::npos) << failed.error();
  EXPECT_FALSE(LeaseNext().has_value());
}

TEST_F(JobCoordinatorTest, ARetryableFailureCountsAnAttemptAHandBackDoesNot) {
  const std::string id = Submit();
  auto granted = LeaseNext();
  ASSERT_TRUE(granted.has_value());
  EXPECT_EQ(Fail(granted->lease_id, true, true).state(), v1::QUEUED);
  EXPECT_EQ(Get(id).attempts(), 0);
  granted = LeaseNext();
  ASSERT_TRUE(granted.has_value());
  EXPECT_EQ(Fail(granted->lease_id, true).state(), v1::QUEUED);
  EXPECT_EQ(Get(id).attempts(), 1);
  granted = LeaseNext();
  ASSERT_TRUE(granted.has_value());
  const v1::Job failed = Fail(granted->lease_id, false);
  EXPECT_EQ(failed.state(), v1::FAILED);
  EXPECT_NE(failed.error().find("worker worker-1: out of memory"), std::string::npos) << failed.error();
  EXPECT_EQ(CodeOf([&] { Fail(granted->lease_id, true); }), ErrorCode::kFailedPrecondition);
}

TEST_F(JobCoordinatorTest, ACancelEndsAQueuedJobAtOnceAndARunningOneAtItsNextReport) {
  const std::string queued = Submit();
  EXPECT_EQ(coordinator_.Cancel(queued, AnonymousPrincipal()).state(), v1::CANCELLED);
  EXPECT_FALSE(LeaseNext().has_value()) << "a cancelled job leaves the queue";

  const std::string running = Submit();
  const auto granted = LeaseNext();
  ASSERT_TRUE(granted.has_value());
  const v1::Job asked = coordinator_.Cancel(running, AnonymousPrincipal());
  EXPECT_EQ(asked.state(), v1::RUNNING);
  EXPECT_TRUE(asked.cancel_requested());
  EXPECT_EQ(Report(granted->lease_id), v1::ProgressReply::STOP_CANCELLED);
  EXPECT_EQ(Get(running).state(), v1::CANCELLED);
  EXPECT_EQ(CodeOf([&] { coordinator_.CheckLease(granted->lease_id); }), ErrorCode::kFailedPrecondition);
}

TEST_F(JobCoordinatorTest, ACancelRacingTheWorkerEndsTheJobOnceAndNeverRequeuesIt) {
  // The worker vanishes after the cancel: cancelled at expiry, not queued again.
  const std::string vanished = Submit();
  ASSERT_TRUE(LeaseNext().has_value());
  coordinator_.Cancel(vanished, AnonymousPrincipal());
  Advance(kTtl + seconds(1));
  EXPECT_EQ(Get(vanished).state(), v1::CANCELLED);
  EXPECT_EQ(Get(vanished).attempts(), 0);

  // The worker fails retryably after the cancel: cancelled, not retried.
  const std::string failing = Submit();
  auto granted = LeaseNext();
  ASSERT_TRUE(granted.has_value());
  coordinator_.Cancel(failing, AnonymousPrincipal());
  EXPECT_EQ(Fail(granted->lease_id, true).state(), v1::CANCELLED);
  EXPECT_FALSE(LeaseNext().has_value());

  // The worker completes before it next reports: its results exist and are kept (SUCCEEDED); a
  // second cancel is then refused as for any finished job.
  const std::string finishing = Submit();
  granted = LeaseNext();
  ASSERT_TRUE(granted.has_value());
  coordinator_.Cancel(finishing, AnonymousPrincipal());
  EXPECT_EQ(Complete(granted->lease_id, Uploaded("metrics.json", "{\"psnr\": 30}")).state(), v1::SUCCEEDED);
  EXPECT_EQ(CodeOf([&] { coordinator_.Cancel(finishing, AnonymousPrincipal()); }),
            ErrorCode::kFailedPrecondition);
}

// A tenant at its byte quota had no way back under it: cancelled and finished jobs kept their bytes
// until retention, which is off by default (found 2026-12-05). Delete removes a settled job's files
// now (not a blob another job shares), marks it expired and its bytes leave the quota; a queued or
// running job or another tenant's is refused; deleting it again is no error and changes nothing.
TEST_F(JobCoordinatorTest, DeletingAFinishedJobsFilesFreesItsTenantsBytes) {
  const Principal a{"a-client", Role::kClient, "a", false};
  const Principal b{"b-client", Role::kClient, "b", false};
  v1::SubmitRequest request;
  *request.mutable_clip() = Uploaded("images/000000.png", "a's frame", "a");
  const std::string first = coordinator_.Submit(request, a).id();
  *request.mutable_clip()->add_files() = Uploaded("images/000001.png", "a's other frame", "a").files(0);
  const std::string second = coordinator_.Submit(request, a).id();  // shares the first frame
  EXPECT_EQ(CodeOf([&] { coordinator_.Delete(first, a); }), ErrorCode::kFailedPrecondition) << "queued";
  const auto granted = LeaseNext();
  ASSERT_TRUE(granted.has_value());
  ASSERT_EQ(granted->job.id(), first);
  EXPECT_EQ(CodeOf([&] { coordinator_.Delete(first, a); }), ErrorCode::kFailedPrecondition) << "running";
  const v1::Manifest result = Uploaded("metrics.json", "{\"psnr\": 31}");
  Complete(granted->lease_id, result);
  const std::int64_t before = store_.UsageOf("a").bytes;
  EXPECT_EQ(CodeOf([&] { coordinator_.Delete(first, b); }), ErrorCode::kNotFound);

  const v1::Job deleted = coordinator_.Delete(first, a);
  EXPECT_GT(deleted.expired_unix_ms(), 0);
  EXPECT_EQ(store_.UsageOf("a").bytes, before - 9 - 12) << "the clip's frame and the result's file";
  EXPECT_FALSE(blobs_.Has(result.files(0).sha256()));
  EXPECT_TRUE(blobs_.Has(request.clip().files(0).sha256())) << "the second job still needs the shared frame";
  const v1::Job again = coordinator_.Delete(first, a);
  EXPECT_EQ(again.expired_unix_ms(), deleted.expired_unix_ms()) << "twice: when its files went, unchanged";
  EXPECT_EQ(store_.UsageOf("a").bytes, before - 9 - 12);
  coordinator_.Cancel(second, a);
  coordinator_.Delete(second, a);
  EXPECT_EQ(store_.UsageOf("a").bytes, 0);
  EXPECT_FALSE(blobs_.Has(request.clip().files(0).sha256()));
}

// The CLI asks before an upload whether the job would be taken: a listing of sizes (no digests, no
// file stored yet) is checked as a submit would check it, and nothing is queued.
TEST_F(JobCoordinatorTest, ACheckBeforeTheUploadQueuesNothing) {
  v1::SubmitRequest request;
  auto* file = request.mutable_clip()->add_files();
  file->set_path("images/000000.png");
  file->set_size(100);
  request.set_name("clip");
  request.set_validate_only(true);
  const v1::Job checked = coordinator_.Submit(request, AnonymousPrincipal());
  EXPECT_TRUE(checked.id().empty());
  EXPECT_EQ(checked.state(), v1::QUEUED);
  EXPECT_EQ(coordinator_.List({}, 10, "", AnonymousPrincipal()).jobs.size(), 0u);
  EXPECT_FALSE(LeaseNext().has_value());
  request.add_send_to("pacs1");
  EXPECT_EQ(CodeOf([&] { coordinator_.Submit(request, AnonymousPrincipal()); }), ErrorCode::kInvalidArgument)
      << "no PACS on this server";
  request.clear_send_to();
  // The training configuration's keys and bounds, as the engine takes them.
  request.mutable_options()->set_config_json(R"({"rays_per_batch": 0})");
  EXPECT_EQ(CodeOf([&] { coordinator_.Submit(request, AnonymousPrincipal()); }), ErrorCode::kInvalidArgument);
  request.mutable_options()->set_config_json(R"({"iteration": 300})");
  EXPECT_EQ(CodeOf([&] { coordinator_.Submit(request, AnonymousPrincipal()); }), ErrorCode::kInvalidArgument);
  request.mutable_options()->set_config_json(R"({"rays_per_batch": 512})");
  EXPECT_TRUE(coordinator_.Submit(request, AnonymousPrincipal()).id().empty());
  request.set_validate_only(false);
  EXPECT_EQ(CodeOf([&] { coordinator_.Submit(request, AnonymousPrincipal()); }), ErrorCode::kInvalidArgument)
      << "a real submit names files with their digests";
}

// A destination given twice made two sends, and the second stayed PENDING for good (the sender works
// on the first of a name): the job could never be deleted (found 2026-12-07). One send per destination.
TEST_F(JobCoordinatorTest, ADestinationGivenTwiceIsSentToOnce) {
  const PacsDirectory pacs({"orthanc=ORTHANC@127.0.0.1:4242", "archive=ARCHIVE@127.0.0.1:4243"});
  std::vector<std::string> sends_asked;
  coordinator_.SetDicomHooks({&pacs, "1.2.3", {}, [&](const std::string& id) { sends_asked.push_back(id); }});
  v1::SubmitRequest request;
  *request.mutable_clip() = Uploaded("images/000000.png", "a frame to send");
  for (const char* name : {"orthanc", "archive", "orthanc"}) request.add_send_to(name);
  const v1::Job job = coordinator_.Submit(request, AnonymousPrincipal());
  ASSERT_EQ(job.sends_size(), 2);
  EXPECT_EQ(job.sends(0).destination(), "orthanc");
  EXPECT_EQ(job.sends(1).destination(), "archive");
  EXPECT_EQ(Get(job.id()).sends_size(), 2);
}

// A FAILED job asked to send was told "results are sent once it has SUCCEEDED", which it never would
// (found 2026-12-07).
TEST_F(JobCoordinatorTest, ASendOfAJobThatEndedWithoutResultsSaysSo) {
  const PacsDirectory pacs({"orthanc=ORTHANC@127.0.0.1:4242"});
  coordinator_.SetDicomHooks({&pacs, "1.2.3", {}, {}});
  const std::string id = Submit();
  EXPECT_NE(testing::ErrorFrom([&] { coordinator_.RequestSend(id, "orthanc", AnonymousPrincipal()); },
                               ErrorCode::kFailedPrecondition)
                .find("is QUEUED; its results can be sent once it has SUCCEEDED"),
            std::string::npos);
  Fail(LeaseNext()->lease_id, /*retry=*/false);
  EXPECT_NE(testing::ErrorFrom([&] { coordinator_.RequestSend(id, "orthanc", AnonymousPrincipal()); },
                               ErrorCode::kFailedPrecondition)
                .find("is FAILED: it ended without results, so none can be sent"),
            std::string::npos);
}

TEST_F(JobCoordinatorTest, AnotherTenantsJobIsNotFoundLikeAMissingOne) {
  v1::SubmitRequest request;
  *request.mutable_clip() = Uploaded("images/000000.png", "tenant a's frame", "a");
  const Principal a{"a-client", Role::kClient, "a", false};
  const Principal b{"b-client", Role::kClient, "b", false};
  const std::string id = coordinator_.Submit(request, a).id();
  EXPECT_EQ(coordinator_.Get(id, a).tenant(), "a");
  EXPECT_EQ(CodeOf([&] { coordinator_.Get(id, b); }), ErrorCode::kNotFound);
  EXPECT_EQ(CodeOf([&] { coordinator_.Cancel(id, b); }), ErrorCode::kNotFound);
  EXPECT_EQ(CodeOf([&] { coordinator_.Get("no-such-job", a); }), ErrorCode::kNotFound);
  EXPECT_EQ(Get(id).state(), v1::QUEUED);
}

// The store keeps each content once, whoever sent it: a tenant that learned a digest of another
// tenant's file named it in a job without uploading it, and got a reconstruction of that patient back
// (found 2026-12-06). Content a tenant does not hold (another's, or no one's: a worker's results
// before its job takes them) is its to name only after it uploads it too; a worker serving one tenant
// names as result or checkpoint only what that tenant holds.
TEST_F(JobCoordinatorTest, AnotherTenantsContentIsNamedOnlyAfterItIsUploadedAgain) {
  const Principal a{"a-client", Role::kClient, "a", false};
  const Principal b{"b-client", Role::kClient, "b", false};
  v1::SubmitRequest theirs;
  *theirs.mutable_clip() = Uploaded("images/000000.png", "b's patient", "b");
  coordinator_.Submit(theirs, b);  // b's job holds the content now
  const auto missing = testing::ErrorFrom(
      [&] {
        v1::SubmitRequest never;
        *never.mutable_clip()->add_files() = theirs.clip().files(0);
        never.mutable_clip()->mutable_files(0)->set_sha256(std::string(64, 'f'));
        coordinator_.Submit(never, a);
      },
      ErrorCode::kFailedPrecondition);
  EXPECT_EQ(testing::ErrorFrom([&] { coordinator_.Submit(theirs, a); }, ErrorCode::kFailedPrecondition),
            missing)
      << "refused as a content never uploaded: the refusal does not tell that b stored it";

  const auto owner = coordinator_.ClientUploadOwner(a);
  EXPECT_EQ(owner.tenant, "a");
  const std::set<std::string> digest{theirs.clip().files(0).sha256()};
  EXPECT_EQ(owner.unproven(theirs.clip()), digest);
  EXPECT_TRUE(coordinator_.ClientUploadOwner(b).unproven(theirs.clip()).empty());
  v1::Manifest no_ones;
  auto* left = no_ones.add_files();
  *left = theirs.clip().files(0);
  left->set_sha256(blobs_.Put("a result no job names yet"));
  left->set_size(25);
  EXPECT_EQ(owner.unproven(no_ones).size(), 1u) << "stored, but not a's";
  EXPECT_EQ(testing::ErrorFrom(
                [&] {
                  v1::SubmitRequest request;
                  *request.mutable_clip() = no_ones;
                  coordinator_.Submit(request, a);
                },
                ErrorCode::kFailedPrecondition),
            missing);
  owner.proven(theirs.clip().files(0).sha256());  // a's upload sent every byte (UploadReceiver)
  EXPECT_TRUE(owner.unproven(theirs.clip()).empty());
  const auto id = coordinator_.Submit(theirs, a).id();

  // A worker serving tenant b cannot name b's content as a's results, nor as a's checkpoint; a worker of
  // every tenant is trusted with every content.
  Scheduler scheduler;
  LeaseTable leases(kTtl);
  WorkerRegistry workers(kTtl);
  JobCoordinator restarted({store_, blobs_, scheduler, leases, workers, hub_, metrics_}, 2, {},
                           [this] { return now_; });
  restarted.Recover();
  EXPECT_EQ(restarted.WorkerUploadOwner("b").unproven(theirs.clip()).size(), 0u) << "b's job holds it";
  const auto result = Uploaded("metrics.json", "{\"psnr\": 31}", "b", &restarted);
  v1::SubmitRequest b_again;
  *b_again.mutable_clip() = result;
  restarted.Submit(b_again, b);  // now b holds the result's content too, a does not
  EXPECT_EQ(restarted.WorkerUploadOwner("a").unproven(result),
            (std::set<std::string>{result.files(0).sha256()}));
  EXPECT_EQ(restarted.WorkerUploadOwner(std::nullopt).unproven, nullptr);
  const auto granted = restarted.Lease("w-a", Clock::now(), "a");
  ASSERT_TRUE(granted.has_value());
  ASSERT_EQ(granted->job.id(), id);
  v1::ProgressUpdate update;
  update.set_lease_id(granted->lease_id);
  *update.mutable_checkpoint() = result.files(0);
  EXPECT_EQ(restarted.Report(update, {}, nullptr, nullptr, "a"), v1::ProgressReply::CONTINUE);
  EXPECT_FALSE(restarted.Get(id, a).has_checkpoint()) << "b's content is no checkpoint of a's job";
  v1::CompleteRequest complete;
  complete.set_lease_id(granted->lease_id);
  *complete.mutable_result() = result;
  std::string refused;  // the job the audit line of the refusal names
  EXPECT_NE(
      testing::ErrorFrom([&] { restarted.Complete(complete, "a", &refused); }, ErrorCode::kFailedPrecondition)
          .find("not uploaded yet"),
      std::string::npos);
  EXPECT_EQ(refused, id);
  EXPECT_EQ(restarted.Get(id, a).state(), v1::RUNNING);
  EXPECT_EQ(restarted.Complete(complete, std::nullopt).state(), v1::SUCCEEDED);
}

// Uploads noted by a server of before proof of possession (uploads.json without "proven") went into
// the shared partial <sha256>.part. The upgrade re-test found 247 MB of an upload not yet submitted
// sent again, and its partial left behind, unlisted (found 2026-12-06). Content only its tenant's
// upload brings, and no other tenant's job names, is now taken as that tenant's, and its partial made
// the tenant's to resume; the rest is sent again.
TEST_F(JobCoordinatorTest, UploadsFromBeforeProofOfPossessionAreTheirTenantsWhereNoOneElseBringsThem) {
  const Principal oncology{"bob", Role::kClient, "oncology", false};
  const std::string complete = "radiology's whole file", half = "radiology's half-sent file",
                    shared = "a file both tenants began", in_job = "oncology's clip file";
  for (const auto* bytes : {&complete, &shared, &in_job}) blobs_.Put(*bytes);
  testing::WriteBytes(dir_ / "blobs" / "partial" / (Sha256Hex(half) + ".part"), half.substr(0, 10));
  v1::SubmitRequest request;
  *request.mutable_clip() = Uploaded("images/000000.png", in_job, "oncology");
  coordinator_.Submit(request, oncology);
  const auto entry = [](const std::string& tenant, const std::string& bytes) {
    return R"({"tenant": ")" + tenant + R"(", "sha256": ")" + Sha256Hex(bytes) + R"(", "bytes": )" +
           std::to_string(bytes.size()) + R"(, "noted_unix_ms": 1765000000000})";
  };
  const auto file = dir_ / "uploads.json";
  testing::WriteBytes(file, "{\"uploads\": [" + entry("radiology", complete) + ", " +
                                entry("radiology", half) + ", " + entry("radiology", shared) + ", " +
                                entry("oncology", shared) + ", " + entry("radiology", in_job) + "]}");

  Scheduler scheduler;
  LeaseTable leases(kTtl);
  WorkerRegistry workers(kTtl);
  JobCoordinator upgraded({store_, blobs_, scheduler, leases, workers, hub_, metrics_}, 2, {},
                          [this] { return now_; });
  upgraded.KeepUploadsIn(file);
  upgraded.Recover();
  const auto unproven = [&](const std::string& tenant, const std::string& bytes) {
    v1::Manifest manifest;
    auto* one = manifest.add_files();
    one->set_path("f");
    one->set_size(static_cast<std::int64_t>(bytes.size()));
    one->set_sha256(Sha256Hex(bytes));
    return !upgraded.ClientUploadOwner(Principal{"x", Role::kClient, tenant, false})
                .unproven(manifest)
                .empty();
  };
  EXPECT_FALSE(unproven("radiology", complete)) << "only radiology's upload brought it: radiology's";
  EXPECT_TRUE(unproven("radiology", shared)) << "oncology's upload brought it too: sent again";
  EXPECT_TRUE(unproven("oncology", shared));
  EXPECT_TRUE(unproven("radiology", in_job)) << "oncology's job names it";
  v1::FileEntry halfway;
  halfway.set_sha256(Sha256Hex(half));
  halfway.set_size(static_cast<std::int64_t>(half.size()));
  EXPECT_EQ(blobs_.Committed(halfway, "radiology"), 10) << "the partial is radiology's to resume";
  EXPECT_EQ(blobs_.Committed(halfway), 0);
  const auto written = testing::ReadBytes(file);
  EXPECT_NE(written.find("\"proven\": true"), std::string::npos) << written;
  EXPECT_NE(written.find("\"proven\": false"), std::string::npos) << written;
  v1::UploadsRequest list;
  list.set_tenant("radiology");
  EXPECT_EQ(upgraded.Uploads(list, AnonymousPrincipal()).tenants(0).arrived_bytes(),
            static_cast<std::int64_t>(complete.size()) + 10)
      << "what arrived: the whole file and the partial's bytes";
}

// A tenant's uploads not yet submitted count against its byte quota: each upload under the quota, and
// none submitted, let a tenant keep any number of them on the data disk for --orphan-hours (found
// 2026-12-06).
// An interrupted upload counted against its tenant's bytes until --orphan-hours (24 h by default),
// and nothing could give it up sooner (found 2026-12-06): `endorecon uploads` lists a tenant's, and
// --drop forgets them and deletes their files, but not a file a job or another tenant's upload holds.
TEST_F(JobCoordinatorTest, UploadsNotYetSubmittedAreListedAndDroppedWithTheFilesNoOneElseHolds) {
  const Principal a{"a-client", Role::kClient, "a", false};
  const Principal b{"b-client", Role::kClient, "b", false};
  const Principal admin{"it-ops", Role::kAdmin, "", false};
  const auto entry = [](const std::string& bytes) {
    v1::FileEntry file;
    file.set_path("images/" + Sha256Hex(bytes).substr(0, 6) + ".png");
    file.set_size(static_cast<std::int64_t>(bytes.size()));
    file.set_sha256(Sha256Hex(bytes));
    return file;
  };
  const std::string complete(100, 'c'), partial(200, 'p'), shared(300, 's'), in_job(400, 'j');
  v1::Manifest uploads;
  for (const auto* bytes : {&complete, &partial, &shared, &in_job}) *uploads.add_files() = entry(*bytes);
  coordinator_.AdmitUpload(uploads, a);
  v1::Manifest theirs;
  *theirs.add_files() = entry(shared);
  coordinator_.AdmitUpload(theirs, b);
  // What arrived: `complete` and `in_job` whole, half of `partial`; `in_job` is the clip of b's job.
  blobs_.Put(complete);
  blobs_.Put(shared);
  blobs_.OpenWriter(entry(partial), "a")->Append(0, partial.substr(0, 100));
  blobs_.Put(in_job);
  for (const auto* bytes : {&complete, &in_job}) coordinator_.ClientUploadOwner(a).proven(Sha256Hex(*bytes));
  coordinator_.ClientUploadOwner(b).proven(Sha256Hex(shared));
  coordinator_.ClientUploadOwner(b).proven(Sha256Hex(in_job));
  v1::SubmitRequest request;
  *request.mutable_clip()->add_files() = entry(in_job);
  coordinator_.Submit(request, b);

  v1::UploadsRequest list;
  const auto listed = coordinator_.Uploads(list, a);
  ASSERT_EQ(listed.tenants_size(), 1);
  EXPECT_EQ(listed.tenants(0).tenant(), "a");
  EXPECT_EQ(listed.tenants(0).files(), 4);
  EXPECT_EQ(listed.tenants(0).bytes(), 1000);
  EXPECT_EQ(listed.tenants(0).arrived_bytes(), 100 + 100 + 400)
      << "complete and in_job whole, half of partial, none of shared (b's upload sent it, a's did not)";
  EXPECT_GT(listed.tenants(0).last_unix_ms(), 0);
  EXPECT_EQ(coordinator_.Uploads(list, admin).tenants_size(), 2) << "an admin sees every tenant's";
  list.set_tenant("a");
  EXPECT_EQ(testing::ErrorFrom([&] { coordinator_.Uploads(list, b); }, ErrorCode::kPermissionDenied),
            "a client token acts on its own tenant's uploads only (tenant 'b')");
  v1::UploadsRequest drop;
  drop.set_drop(true);
  EXPECT_NE(testing::ErrorFrom([&] { coordinator_.Uploads(drop, admin); }).find("name the tenant"),
            std::string::npos);

  const auto dropped = coordinator_.Uploads(drop, a);
  ASSERT_EQ(dropped.tenants_size(), 1);
  EXPECT_EQ(dropped.tenants(0).bytes(), 1000) << "what it dropped";
  EXPECT_FALSE(dropped.has_deleted_files())
      << "a client is not told: it would say which files another tenant holds";
  EXPECT_FALSE(blobs_.Has(Sha256Hex(complete)));
  EXPECT_EQ(blobs_.Committed(entry(partial), "a"), 0) << "the partial went";
  EXPECT_TRUE(blobs_.Has(Sha256Hex(shared))) << "b's upload brings it too";
  EXPECT_TRUE(blobs_.Has(Sha256Hex(in_job))) << "b's job holds it";
  EXPECT_EQ(coordinator_.Uploads(v1::UploadsRequest(), a).tenants_size(), 0);
  const auto left = coordinator_.Uploads(v1::UploadsRequest(), admin);
  ASSERT_EQ(left.tenants_size(), 1);
  EXPECT_EQ(left.tenants(0).tenant(), "b");
  EXPECT_EQ(left.tenants(0).bytes(), 300);
  // a gave its uploads up: it holds none of their content any more, though b's job and upload keep
  // some of it stored (a submit of it was accepted until a restart; found 2026-12-06).
  v1::Manifest given_up;
  for (const auto* bytes : {&shared, &in_job}) *given_up.add_files() = entry(*bytes);
  EXPECT_EQ(coordinator_.ClientUploadOwner(a).unproven(given_up).size(), 2u);
  EXPECT_TRUE(coordinator_.ClientUploadOwner(b).unproven(given_up).empty());
  // An admin's drop is told what it deleted: b's upload of `shared`, which no job holds.
  drop.set_tenant("b");
  const auto admins = coordinator_.Uploads(drop, admin);
  ASSERT_TRUE(admins.has_deleted_files());
  EXPECT_EQ(admins.deleted_files(), 1);
  EXPECT_EQ(admins.deleted_bytes(), 300);
  EXPECT_FALSE(blobs_.Has(Sha256Hex(shared)));
}

// Deleting a job, or its retention, keeps the files another tenant's upload not yet submitted
// brings: deleting one tenant's job deleted what another's interrupted upload of the same content
// had sent, and `uploads` showed it gone (found 2026-12-06).
TEST_F(JobCoordinatorTest, DeletingAJobKeepsTheFilesAnUploadNotYetSubmittedBrings) {
  const Principal a{"a-client", Role::kClient, "a", false};
  const Principal b{"b-client", Role::kClient, "b", false};
  const std::string shared(300, 's'), own(200, 'o');
  v1::Manifest theirs;
  auto* file = theirs.add_files();
  file->set_path("images/000000.png");
  file->set_size(static_cast<std::int64_t>(shared.size()));
  file->set_sha256(Sha256Hex(shared));
  coordinator_.AdmitUpload(theirs, b);  // b's upload, interrupted once the file had arrived
  blobs_.Put(shared);
  coordinator_.ClientUploadOwner(b).proven(Sha256Hex(shared));
  const auto arrived = [&] {
    return coordinator_.Uploads(v1::UploadsRequest(), b).tenants(0).arrived_bytes();
  };
  ASSERT_EQ(arrived(), 300);

  for (const bool by_retention : {false, true}) {
    SCOPED_TRACE(by_retention ? "retention" : "delete");
    v1::SubmitRequest request;
    *request.mutable_clip() = Uploaded("images/000000.png", shared, "a");
    *request.mutable_clip()->add_files() =
        Uploaded("images/000001.png", own + (by_retention ? "r" : ""), "a").files(0);
    const std::string id = coordinator_.Submit(request, a).id();
    coordinator_.Cancel(id, a);
    if (by_retention) {
      coordinator_.ExpireFinishedBefore(std::numeric_limits<std::int64_t>::max());
    } else {
      coordinator_.Delete(id, a);
    }
    EXPECT_GT(Get(id).expired_unix_ms(), 0);
    EXPECT_FALSE(blobs_.Has(Sha256Hex(own + (by_retention ? "r" : "")))) << "a's own file went";
    EXPECT_TRUE(blobs_.Has(Sha256Hex(shared))) << "b's upload brings it";
    EXPECT_EQ(arrived(), 300);
  }
}

TEST_F(JobCoordinatorTest, UploadsNotYetSubmittedCountAgainstTheByteQuota) {
  JobCoordinator quoted({store_, blobs_, scheduler_, leases_, workers_, hub_, metrics_}, 2,
                        TenantQuotas({0, 1000}, ""), [this] { return now_; });
  const Principal a{"a-client", Role::kClient, "a", false};
  const Principal b{"b-client", Role::kClient, "b", false};
  const auto upload = [](const std::string& bytes) {
    v1::Manifest manifest;
    auto* file = manifest.add_files();
    file->set_path("images/000000.png");
    file->set_size(static_cast<std::int64_t>(bytes.size()));
    file->set_sha256(Sha256Hex(bytes));
    return manifest;
  };
  const std::string first(600, '1'), second(600, '2');
  const auto refusal = [&](const v1::Manifest& manifest, const Principal& who) -> std::string {
    try {
      quoted.AdmitUpload(manifest, who);
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), ErrorCode::kResourceExhausted);
      return e.what();
    }
    return "";
  };
  EXPECT_EQ(refusal(upload(first), a), "");
  EXPECT_EQ(refusal(upload(first), a), "") << "an upload resumed is not counted twice";
  std::string message = refusal(upload(second), a);
  EXPECT_NE(
      message.find("tenant 'a' keeps 0 bytes in its jobs, 600 in uploads not yet submitted (the last at 20"),
      std::string::npos)
      << message;
  EXPECT_NE(
      message.find("or finish an upload not yet submitted (`endorecon submit` of the same clip resumes and "
                   "submits it), or give those up (`endorecon uploads --drop`)"),
      std::string::npos)
      << message;
  quoted.CheckUploadQuota(upload(second), a);  // a listing before an upload: not counted there
  EXPECT_EQ(refusal(upload(second), b), "") << "another tenant's uploads are its own";

  // Submitted, the upload's bytes are the job's, counted once.
  blobs_.Put(first);
  quoted.ClientUploadOwner(a).proven(Sha256Hex(first));
  v1::SubmitRequest request;
  *request.mutable_clip() = upload(first);
  quoted.Submit(request, a);
  message = refusal(upload(second), a);
  EXPECT_NE(message.find("tenant 'a' keeps 600 bytes in its jobs and this adds 600"), std::string::npos)
      << message;
  EXPECT_EQ(refusal(upload(std::string(300, '3')), a), "");
  message = refusal(upload(std::string(300, '4')), a);
  EXPECT_NE(message.find("600 bytes in its jobs, 300 in uploads not yet submitted"), std::string::npos)
      << message;
  // Retention forgets an upload as it deletes its partial: after --orphan-hours.
  quoted.ExpireFinishedBefore(
      0, {UploadLedger::Time::clock::now() + seconds(1), std::numeric_limits<std::int64_t>::max()});
  EXPECT_EQ(refusal(upload(std::string(300, '4')), a), "");
}

// A lease call its worker cancelled (a worker stopping cancels its calls, then leaves) takes no job:
// one took the next job 4 s after its worker had stopped (found 2026-12-06).
TEST_F(JobCoordinatorTest, ACancelledLeaseCallTakesNoJobAndEndsWithoutWaitingItsDeadline) {
  std::atomic<bool> cancelled{false};
  const auto started = Clock::now();
  std::thread canceller([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
    cancelled = true;
  });
  EXPECT_FALSE(coordinator_.Lease("worker-1", Clock::now() + seconds(20), std::nullopt,
                                  [&] { return cancelled.load(); }));
  canceller.join();
  EXPECT_LT(Clock::now() - started, seconds(5))
      << "it ended within a slice of its cancel, not at its deadline";
  const std::string id = Submit();
  EXPECT_FALSE(coordinator_.Lease("worker-1", Clock::now() + seconds(20), std::nullopt, [] { return true; }));
  EXPECT_EQ(Get(id).state(), v1::QUEUED);
  const auto granted = LeaseNext("worker-2");
  ASSERT_TRUE(granted.has_value());
  EXPECT_EQ(granted->job.id(), id);
}

}  // namespace
}  // namespace endorecon::server
