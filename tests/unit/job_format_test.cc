// What `endorecon watch` prints for a progress event: every number the engine streams, each shown
// only once it has been measured.
#include "client/job_format.h"

#include <gtest/gtest.h>

#include <cmath>

namespace endorecon::client {
namespace {

v1::Progress MidRun() {
  v1::Progress p;
  p.set_iteration(2500);
  p.set_total_iterations(10000);
  p.set_seconds(61.4);
  p.set_loss(0.01234);
  p.set_train_psnr(33.456);
  p.set_samples_per_second(2.05e6);
  p.set_eta_s(187);
  p.set_heldout_psnr(-1);
  p.set_depth_rmse(-1);
  return p;
}

TEST(ProgressLine, ShowsIterationTimeLossPsnrThroughputAndEta) {
  const std::string line = ProgressLine(MidRun());
  EXPECT_EQ(line.rfind("[######..................]  25%", 0), 0u) << line;
  for (const char* part :
       {"it 2500/10000", "61 s", "loss 0.01234", "PSNR 33.46 dB", "2.05e+06 samples/s", "ETA 3m07s"}) {
    EXPECT_NE(line.find(part), std::string::npos) << "missing '" << part << "' in: " << line;
  }
  // Not measured yet (-1): not shown.
  EXPECT_EQ(line.find("held-out"), std::string::npos) << line;
  EXPECT_EQ(line.find("depth"), std::string::npos) << line;
}

TEST(ProgressLine, ShowsHeldOutPsnrAndDepthErrorOnceMeasured) {
  v1::Progress p = MidRun();
  p.set_heldout_psnr(31.237);
  p.set_depth_rmse(0.0125);
  const std::string line = ProgressLine(p);
  EXPECT_NE(line.find("PSNR 33.46 dB (held-out 31.24)"), std::string::npos) << line;
  EXPECT_NE(line.find("depth RMSE 1.25% of range"), std::string::npos) << line;
}

TEST(ProgressLine, SaysWhenTheResultsAreBeingRendered) {
  v1::Progress p = MidRun();
  p.set_phase("evaluate");
  p.set_iteration(12);
  p.set_total_iterations(48);
  p.set_seconds(6);
  p.set_eta_s(18);
  EXPECT_EQ(ProgressLine(p), "evaluating the results: frame 12/48  6 s  ETA 18s");
}

// The results' upload took minutes after "evaluating the results: frame 3813/3813 ETA 0s" stood still
// (found 2026-12-06).
TEST(ProgressLine, SaysWhenTheResultsAreBeingUploaded) {
  v1::Progress p;
  p.set_phase("upload");
  p.set_total_iterations(538);
  EXPECT_EQ(ProgressLine(p), "uploading the results: 538 file(s)");
}

TEST(ProgressLine, ClampsTheBarAndHandlesAnUnknownTotal) {
  v1::Progress p = MidRun();
  p.set_iteration(12000);
  EXPECT_EQ(ProgressLine(p).rfind("[########################] 100%", 0), 0u) << ProgressLine(p);
  p.set_total_iterations(0);
  EXPECT_EQ(ProgressLine(p).rfind("[........................]   0%", 0), 0u) << ProgressLine(p);
}

v1::Job Finished(v1::JobState state) {
  v1::Job job;
  job.set_id("0123456789ab");
  job.set_state(state);
  job.set_started_unix_ms(1'000'000);
  job.set_finished_unix_ms(1'062'000);
  *job.mutable_progress() = MidRun();
  job.mutable_progress()->set_phase("evaluate");
  job.mutable_progress()->set_iteration(48);
  job.mutable_progress()->set_total_iterations(48);
  return job;
}

TEST(DescribeJob, ASucceededJobShowsItsOutcomeNotItsLastProgress) {
  v1::Job job = Finished(v1::SUCCEEDED);
  job.set_summary_json(
      R"({"iterations":1858,"train_seconds":41.2,"train_psnr":31.1,"heldout_psnr":31.754,"metrics":"metrics.json"})");
  EXPECT_EQ(OutcomeLine(job),
            "done: 1858 iterations in 41s of training, 1m02s in all, PSNR 31.10 dB (held-out 31.75)");
  const std::string text = DescribeJob(job);
  EXPECT_NE(text.find("  outcome   done: 1858 iterations"), std::string::npos) << text;
  EXPECT_EQ(text.find("evaluating the results"), std::string::npos) << text;
  EXPECT_NE(text.find("  started   " + HumanTime(1'000'000) + " (its latest lease)"), std::string::npos)
      << "a record without its first start may show a later lease's: " << text;
  EXPECT_EQ(text.find("restarted"), std::string::npos) << "one lease: " << text;
  job.set_first_started_unix_ms(1'000'000);
  EXPECT_NE(DescribeJob(job).find("  started   " + HumanTime(1'000'000) + "\n"), std::string::npos)
      << "one lease: " << DescribeJob(job);
  // A requeued job started again: its first start and its latest lease's.
  job.set_first_started_unix_ms(400'000);
  const std::string requeued = DescribeJob(job);
  EXPECT_NE(requeued.find("  started   " + HumanTime(400'000) + "\n"), std::string::npos) << requeued;
  EXPECT_NE(requeued.find("  restarted " + HumanTime(1'000'000) + " (its latest lease)"), std::string::npos)
      << requeued;
  // Its training seconds count both runs: its wall time is said for the last run and since the first.
  EXPECT_EQ(OutcomeLine(job),
            "done: 1858 iterations in 41s of training, 1m02s in its last run, 11m02s since it first "
            "started, PSNR 31.10 dB (held-out 31.75)");
  job.set_first_started_unix_ms(1'000'000);
  // Without held-out frames the engine reports -1: not shown.
  job.set_summary_json(R"({"iterations":10,"train_seconds":1,"train_psnr":20,"heldout_psnr":-1})");
  EXPECT_EQ(OutcomeLine(job).find("held-out"), std::string::npos) << OutcomeLine(job);
  // A budget too small for the clip's results: which one would have left training three quarters.
  job.set_summary_json(
      R"({"iterations":2211,"train_seconds":74.1,"train_psnr":24.05,"heldout_psnr":23.13,"budget_advised_s":190})");
  EXPECT_EQ(
      OutcomeLine(job),
      "done: 2211 iterations in 1m14s of training, 1m02s in all, PSNR 24.05 dB (held-out 23.13); its "
      "results took more than a quarter of the time budget: 190 s or more leaves training three quarters");
  // A run over its budget says by how much (within a tenth it is on time).
  job.set_summary_json(
      R"({"iterations":120,"train_seconds":12,"train_psnr":24,"heldout_psnr":23,"time_budget_s":30,)"
      R"("run_seconds":62.9,"budget_advised_s":230})");
  EXPECT_NE(OutcomeLine(job).find(
                "; the reconstruction took 1m03s of its 30s time budget; its results took more than"),
            std::string::npos)
      << OutcomeLine(job);
  job.set_summary_json(
      R"({"iterations":120,"train_seconds":12,"train_psnr":24,"time_budget_s":30,"run_seconds":32.9})");
  EXPECT_EQ(OutcomeLine(job).find("time budget"), std::string::npos) << OutcomeLine(job);
  // The run's warnings (metrics.json "warnings"), each on a line of its own under the outcome.
  job.set_summary_json(
      R"({"iterations":40,"train_seconds":1,"train_psnr":8,"warnings":["the reconstruction learnt nothing",)"
      R"("mesh.ply: no triangle\u001b[2J"]})");
  EXPECT_NE(DescribeJob(job).find("PSNR 8.00 dB\n  warning   the reconstruction learnt nothing\n  warning   "
                                  "mesh.ply: no triangle"),
            std::string::npos)
      << DescribeJob(job);
  EXPECT_EQ(DescribeJob(job).find("\x1b"), std::string::npos) << "a control character goes to no terminal";
}

// The frames --frames picked of a DICOM recording are shown with the clip.
TEST(DescribeJob, TheClipLineSaysWhichFramesWerePicked) {
  v1::Job job;
  job.set_id("0123456789ab");
  job.mutable_clip()->add_files()->set_path("poses_bounds.npy");
  EXPECT_NE(DescribeJob(job).find("  clip      1 file(s)\n"), std::string::npos) << DescribeJob(job);
  job.mutable_recording()->set_frames("0:500:2");
  EXPECT_NE(DescribeJob(job).find("  clip      1 file(s) (frames 0:500:2)\n"), std::string::npos)
      << DescribeJob(job);
}

// A raw recording's line says it was prepared, and which eye's first frames were dropped.
TEST(DescribeJob, TheRecordingLineSaysWhichEyesFirstFramesWereSkipped) {
  v1::Job job;
  job.set_id("0123456789ab");
  job.mutable_clip()->add_files()->set_path("left.mp4");
  job.mutable_clip()->add_files()->set_path("right.mp4");
  job.mutable_prepare()->set_rectified(true);
  EXPECT_NE(DescribeJob(job).find("  recording 2 file(s) (prepared into the results' clip/)\n"),
            std::string::npos)
      << DescribeJob(job);
  job.mutable_prepare()->set_skip_left(9);
  EXPECT_NE(
      DescribeJob(job).find("  recording 2 file(s) (prepared into the results' clip/, --skip-left 9)\n"),
      std::string::npos)
      << DescribeJob(job);
}

TEST(DescribeJob, TheIterationsTrainedComeFromTheSummary) {
  v1::Job job = Finished(v1::SUCCEEDED);
  EXPECT_FALSE(TrainedIterations(job).has_value());
  job.set_summary_json(R"({"iterations":1858,"train_seconds":41.2})");
  EXPECT_EQ(TrainedIterations(job), 1858);
  job.set_summary_json("not json");
  EXPECT_FALSE(TrainedIterations(job).has_value());
}

TEST(DescribeJob, AJobThatEndedOtherwiseShowsWhereItStopped) {
  v1::Job job = Finished(v1::FAILED);
  job.set_summary_json(R"({"iterations":1858})");  // not a success: no outcome
  EXPECT_EQ(OutcomeLine(job), "");
  EXPECT_NE(DescribeJob(job).find("  stopped   evaluating the results: frame 48/48"), std::string::npos)
      << DescribeJob(job);
  EXPECT_EQ(DescribeJob(job).find("ETA"), std::string::npos) << DescribeJob(job);  // it ended
  job = Finished(v1::SUCCEEDED);
  job.set_summary_json("not json");  // unreadable: the last progress, as a stopped job's
  EXPECT_EQ(OutcomeLine(job), "");
  EXPECT_NE(DescribeJob(job).find("  stopped   "), std::string::npos) << DescribeJob(job);
  job = Finished(v1::RUNNING);
  job.set_finished_unix_ms(0);
  EXPECT_NE(DescribeJob(job).find("  progress  "), std::string::npos) << DescribeJob(job);
  // Requeued: where its last run stopped, without an ETA, and why it was requeued; running again,
  // that reason is said as the requeue's, not the job's.
  job.set_error("worker w1 stopped reporting; its lease expired");
  EXPECT_NE(DescribeJob(job).find("  requeued  worker w1 stopped reporting"), std::string::npos)
      << DescribeJob(job);
  job.set_state(v1::QUEUED);
  EXPECT_NE(DescribeJob(job).find("  last run  "), std::string::npos) << DescribeJob(job);
  EXPECT_EQ(DescribeJob(job).find("ETA"), std::string::npos) << DescribeJob(job);
}

TEST(HumanUnits, DurationsAndBytes) {
  EXPECT_EQ(HumanDuration(42.4), "42s");
  EXPECT_EQ(HumanDuration(187), "3m07s");
  EXPECT_EQ(HumanDuration(7500), "2h05m");
  EXPECT_EQ(HumanDuration(-5), "0s");
  EXPECT_EQ(HumanDuration(1e300), "8888888h53m") << "clamped, not overflowed";
  EXPECT_EQ(HumanDuration(std::nan("")), "0s");
  EXPECT_EQ(HumanBytes(999), "999 B");
  EXPECT_EQ(HumanBytes(1234567), "1.2 MB");
}

}  // namespace
}  // namespace endorecon::client
