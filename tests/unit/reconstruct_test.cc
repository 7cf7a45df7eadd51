// Whole runs through Reconstruct: each run keeps the thread count it was given, also when two run at
// once in one process (a worker serving two devices), and says so in metrics.json.
#include "worker/engine/reconstruct.h"

#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <thread>
#include <vector>

#include "common/json_file.h"
#include "tests/integration/sanitizer_build.h"
#include "tests/unit/clip_fixture.h"
#include "tests/unit/temp_dir.h"
#include "worker/engine/scene/synthetic_clip.h"

namespace endorecon {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

struct Observed {
  ReconstructSummary summary;
  int concurrency_in_hooks = 0;  // the arena the run's hooks were called in
  Clock::time_point first, last;
  nlohmann::json metrics;
};

// A small synthetic clip (8 frames of 40 x 32) at `dir`.
void WriteSmallClip(const fs::path& dir) {
  scene::SynthOptions synth;
  synth.frames = 8;
  synth.width = 40;
  synth.height = 32;
  scene::WriteSyntheticClip(synth, dir);
}

// A cheap configuration for runs on that clip.
nlohmann::json SmallRunConfig() {
  return {{"rays_per_batch", 256}, {"mc_passes", 1}, {"eval_coarse_samples", 8}, {"eval_fine_samples", 8}};
}

// A run of that configuration on `clip` into `out`, every 4th frame held out.
ReconstructOptions SmallRunOptions(const fs::path& clip, const fs::path& out) {
  ReconstructOptions options;
  options.clip_dir = clip.string();
  options.out_dir = out.string();
  options.holdout = 4;
  options.config = SmallRunConfig();
  return options;
}

Observed RunReconstruct(const fs::path& clip, const fs::path& out, int threads) {
  ReconstructOptions options = SmallRunOptions(clip, out);
  options.threads = threads;
  options.iterations = 60;
  Observed observed;
  ReconstructHooks hooks;
  hooks.progress_interval_s = 0;
  hooks.on_progress = [&](const Progress&) {
    observed.concurrency_in_hooks = tbb::this_task_arena::max_concurrency();
    if (observed.first == Clock::time_point()) observed.first = Clock::now();
    observed.last = Clock::now();
  };
  observed.summary = Reconstruct(options, hooks);
  std::ifstream(out / "metrics.json") >> observed.metrics;
  return observed;
}

TEST(Reconstruct, TwoRunsInOneProcessEachKeepTheirThreadCount) {
  testing::TempDir dir("reconstruct-threads");
  WriteSmallClip(dir / "clip");
  Observed one, two;
  std::thread a([&] { one = RunReconstruct(dir / "clip", dir / "one", 1); });
  std::thread b([&] { two = RunReconstruct(dir / "clip", dir / "two", 2); });
  a.join();
  b.join();
  EXPECT_EQ(one.summary.threads, 1);
  EXPECT_EQ(two.summary.threads, 2);
  EXPECT_EQ(one.metrics.at("threads"), 1);
  EXPECT_EQ(two.metrics.at("threads"), 2);
  EXPECT_EQ(one.concurrency_in_hooks, 1);
  EXPECT_EQ(two.concurrency_in_hooks, 2);
  // They did run at the same time.
  EXPECT_LT(one.first, two.last);
  EXPECT_LT(two.first, one.last);
  EXPECT_EQ(one.summary.iterations, 60);
  EXPECT_EQ(two.summary.iterations, 60);
}

// A run ended by its time budget, far below its iteration cap: the progress it reports goes on
// towards 100% of the budget (not of the cap), and its last report is the run's end.
TEST(Reconstruct, ProgressUnderABudgetEndsAtTheIterationsRun) {
  testing::TempDir dir("reconstruct-budget");
  WriteSmallClip(dir / "clip");
  ReconstructOptions options = SmallRunOptions(dir / "clip", dir / "out");
  options.iterations = 1'000'000;
  // Instrumented builds step ~5x slower: the budget scales so that it still holds many reports.
  options.time_budget_s = 1.5 * testing::kSlowdown;
  std::vector<Progress> reports;
  ReconstructHooks hooks;
  hooks.progress_interval_s =
      0.05;  // several reports even when a loaded machine leaves training a fraction of the budget
  hooks.on_progress = [&](const Progress& p) { reports.push_back(p); };
  const ReconstructSummary summary = Reconstruct(options, hooks);
  // Training's reports, then evaluation's (frames done of all, ending complete).
  std::vector<Progress> evaluating;
  while (!reports.empty() && reports.back().phase == "evaluate") {
    evaluating.insert(evaluating.begin(), reports.back());
    reports.pop_back();
  }
  ASSERT_EQ(evaluating.size(), 8u) << "one report per frame";
  EXPECT_EQ(evaluating.back().iteration, 8);
  EXPECT_EQ(evaluating.back().total_iterations, 8);
  EXPECT_EQ(evaluating.back().eta_s, 0);
  ASSERT_GE(reports.size(), 2u);
  for (const Progress& p : reports) EXPECT_EQ(p.phase, "");
  const Progress& last = reports.back();
  EXPECT_EQ(last.iteration, summary.iterations);
  EXPECT_EQ(last.total_iterations, summary.iterations) << "the last report says the run is complete";
  EXPECT_EQ(last.eta_s, 0);
  EXPECT_LT(summary.iterations, 1'000'000);
  // ... and its rate is the run's average, not the last interval's (which may hold no step).
  const double average = ReadJsonFile(dir / "out" / "metrics.json").at("samples_per_second");
  EXPECT_GT(average, 0);
  EXPECT_NEAR(last.samples_per_second, average, 1e-6 * average);
  const Progress& middle = reports[reports.size() / 2];
  const double share = static_cast<double>(middle.iteration) / middle.total_iterations;
  // The training budget is the run's less what evaluation and writing will need: the share done is
  // the training seconds against that (seconds + ETA), and below the share of the whole budget's.
  EXPECT_NEAR(share, middle.seconds / (middle.seconds + middle.eta_s), 0.1) << "the share done is on time";
  EXPECT_GT(share, middle.seconds / options.time_budget_s - 0.05);

  // metrics.json says where the run's time went and how each frame was rendered.
  const nlohmann::json metrics = ReadJsonFile(dir / "out" / "metrics.json");
  const auto& time = metrics.at("time");
  EXPECT_EQ(time.at("budget_s").get<double>(), options.time_budget_s);
  EXPECT_LT(time.at("training_steps_s").get<double>(), time.at("training_s").get<double>() + 1e-9);
  EXPECT_LT(time.at("training_s").get<double>() + time.at("evaluation_s").get<double>(),
            time.at("total_s").get<double>());
  const auto& evaluation = metrics.at("evaluation");
  const std::size_t rendered = evaluation.at("full_frames").size() +
                               evaluation.value("reduced_frames", nlohmann::json::array()).size();
  EXPECT_EQ(rendered, 8u);
  if (evaluation.contains("reduced_frames")) {  // the training frames' PSNR by render, 6 in all
    const auto& by_render = evaluation.at("train_psnr_tissue");  // a render no training frame had: absent
    const auto count = [&](const char* render) {
      return by_render.contains(render) ? by_render.at(render).at("count").get<int>() : 0;
    };
    EXPECT_EQ(count("full") + count("reduced"), 6);
    // The depth the same way (the clip has ground-truth depth).
    const auto& depth = evaluation.at("train_depth_rmse");
    const auto depth_count = [&](const char* render) {
      return depth.contains(render) ? depth.at(render).at("count").get<int>() : 0;
    };
    EXPECT_EQ(depth_count("full") + depth_count("reduced"), 6);
  }
  // The deformation started from the training frames' optical flow (the clip has depth, moves, and
  // trains on its frame at time 0): 5 frames besides that one.
  const auto& start = metrics.at("deformation_start");
  EXPECT_EQ(start.at("from"), "optical flow") << start.dump();
  EXPECT_GE(start.value("frames", 0), 4) << start.dump();
  EXPECT_EQ(start.value("depth", ""), "priors") << start.dump();
  // A held-out frame is full, or (a budget too small to afford it) listed as reduced.
  const auto listed = [](const nlohmann::json& frames, int f) {
    return std::find(frames.begin(), frames.end(), f) != frames.end();
  };
  for (int f : metrics.at("heldout").at("frames")) {
    const bool full = listed(evaluation.at("full_frames"), f);
    const bool reduced = listed(evaluation.value("heldout_reduced", nlohmann::json::array()), f);
    EXPECT_NE(full, reduced) << "held-out frame " << f;
  }
  // The leanest plan's price, and (only when it is more than a quarter of the budget) the budget that
  // would have left training three quarters: above this one.
  const double least = evaluation.at("seconds").at("render_least");
  EXPECT_GT(least, 0);
  if (least > 0.25 * options.time_budget_s) {
    ASSERT_TRUE(time.contains("budget_advised_s")) << time.dump();
    EXPECT_GE(time.at("budget_advised_s").get<double>(), 4 * least);
    EXPECT_GT(time.at("budget_advised_s").get<double>(), options.time_budget_s);
  } else {
    EXPECT_FALSE(time.contains("budget_advised_s")) << time.dump();
  }
}

// Results that cost more than evaluation's quarter of the budget (many dropout passes on a short
// budget): the run says, in metrics.json and the log, which budget would have left training its three
// quarters.
TEST(Reconstruct, ABudgetTooSmallForItsResultsSaysWhichWouldDo) {
  testing::TempDir dir("reconstruct-advice");
  WriteSmallClip(dir / "clip");
  ReconstructOptions options = SmallRunOptions(dir / "clip", dir / "out");
  options.time_budget_s = 1.0 * testing::kSlowdown;
  options.config["mc_passes"] = 64;
  options.config["eval_coarse_samples"] = options.config["eval_fine_samples"] = 32;
  Reconstruct(options, {});
  const nlohmann::json metrics = ReadJsonFile(dir / "out" / "metrics.json");
  const double least = metrics.at("evaluation").at("seconds").at("render_least");
  EXPECT_GT(least, 0.25 * options.time_budget_s)
      << "the test's premise: the results cost more than a quarter";
  const auto& time = metrics.at("time");
  ASSERT_TRUE(time.contains("budget_advised_s")) << time.dump();
  const double advised = time.at("budget_advised_s");
  EXPECT_GE(advised, 4 * least);
  EXPECT_LT(advised, 4 * least + 20) << "within rounding and the writing";
  EXPECT_EQ(std::fmod(advised, 10.0), 0.0);
}

// A budget spent before training starts (loading the clip and pricing its results take longer):
// training takes one step and the run goes on to its results, instead of reading the spent budget
// as none and training until the next progress update.
TEST(Reconstruct, ABudgetSpentBeforeTrainingTrainsOneStep) {
  testing::TempDir dir("reconstruct-spent");
  WriteSmallClip(dir / "clip");
  ReconstructOptions options = SmallRunOptions(dir / "clip", dir / "out");
  options.time_budget_s = 1e-3;
  ReconstructHooks hooks;
  hooks.progress_interval_s = 3;  // the budget's next update; until it, a budget read as none trains on
  const ReconstructSummary summary = Reconstruct(options, hooks);
  EXPECT_EQ(summary.iterations, 1);
  EXPECT_TRUE(fs::exists(dir / "out" / "metrics.json"));
}

// Results asked into the clip's own folder would overwrite its depth/ with the rendered depth: the
// run is refused before anything is written there.
TEST(Reconstruct, ResultsAreNotWrittenOverTheClip) {
  testing::TempDir dir("reconstruct-over-clip");
  WriteSmallClip(dir / "clip");
  const auto files = [&] {
    std::size_t n = 0;
    for (const auto& entry : fs::recursive_directory_iterator(dir / "clip")) n += entry.is_regular_file();
    return n;
  };
  const std::size_t before = files();
  ReconstructOptions options = SmallRunOptions(dir / "clip", dir / "clip" / ".");
  const std::string message = testing::ErrorFrom([&] { Reconstruct(options, {}); });
  EXPECT_NE(message.find("is the clip's folder"), std::string::npos) << message;
  EXPECT_EQ(files(), before);
}

// A refused resume writes nothing: it left a folder holding only config.json, which a later render
// took for a reconstruction's results.
TEST(Reconstruct, ARefusedResumeLeavesNoResultsFolder) {
  testing::TempDir dir("reconstruct-refused-resume");
  WriteSmallClip(dir / "clip");
  testing::WriteBytes(dir / "not-a-checkpoint.bin", "hello");
  ReconstructOptions options = SmallRunOptions(dir / "clip", dir / "out");
  options.resume_from = (dir / "not-a-checkpoint.bin").string();
  options.iterations = 5;
  const std::string message = testing::ErrorFrom([&] { Reconstruct(options, {}); });
  EXPECT_NE(message.find("not-a-checkpoint.bin"), std::string::npos) << message;
  EXPECT_FALSE(fs::exists(dir / "out")) << message;
}

// Without a time budget evaluation still keeps to about a quarter of the run, but nothing is late:
// the held-out frames are rendered in full however short the training was.
TEST(Reconstruct, WithoutABudgetHeldOutFramesAreNeverReduced) {
  testing::TempDir dir("reconstruct-no-budget");
  WriteSmallClip(dir / "clip");
  ReconstructOptions options = SmallRunOptions(dir / "clip", dir / "out");
  options.iterations = 5;
  options.config["mc_passes"] = 16;
  Reconstruct(options, {});
  const nlohmann::json evaluation = ReadJsonFile(dir / "out" / "metrics.json").at("evaluation");
  ASSERT_TRUE(evaluation.contains("reduced_frames")) << "the test's premise: evaluation was cut to its share";
  EXPECT_FALSE(evaluation.contains("heldout_reduced")) << evaluation.dump();
  // The held-out frames (3 and 7) are full; a training frame may be too when the run's quarter
  // allows it, which depends on how long training took (a loaded machine gave [3, 6, 7]).
  const auto full = evaluation.at("full_frames").get<std::vector<int>>();
  for (const int held_out : {3, 7})
    EXPECT_NE(std::find(full.begin(), full.end(), held_out), full.end()) << held_out;
}

// A resume may change settings the uncertainty map's stride is fitted from (here the refresh
// interval, which would make it 8); the map comes back from the checkpoint at the stride it was laid
// out with (4), so the run resumes instead of failing on the map's cell count.
TEST(Reconstruct, AResumeKeepsItsCheckpointsUncertaintyMapStride) {
  testing::TempDir dir("reconstruct-resume-stride");
  WriteSmallClip(dir / "clip");
  ReconstructOptions first = SmallRunOptions(dir / "clip", dir / "first");
  first.iterations = 20;
  Reconstruct(first, {});
  EXPECT_EQ(ReadJsonFile(dir / "first" / "config.json").at("train").at("adaptive_map_stride"), 4);

  ReconstructOptions resumed = SmallRunOptions(dir / "clip", dir / "resumed");
  resumed.resume_from = (dir / "first" / "model" / "checkpoint.bin").string();
  resumed.iterations = 30;
  resumed.config = {{"adaptive_refresh", 5}};
  ReconstructOptions fresh = resumed;
  fresh.resume_from.clear();
  fresh.out_dir = (dir / "fresh").string();
  fresh.config = SmallRunConfig();
  fresh.config["adaptive_refresh"] = 5;
  fresh.iterations = 10;
  Reconstruct(fresh, {});
  EXPECT_EQ(ReadJsonFile(dir / "fresh" / "config.json").at("train").at("adaptive_map_stride"), 8)
      << "the test's premise: these settings fit another stride";

  const ReconstructSummary summary = Reconstruct(resumed, {});
  EXPECT_EQ(summary.iterations, 30);
  const nlohmann::json config = ReadJsonFile(dir / "resumed" / "config.json").at("train");
  EXPECT_EQ(config.at("adaptive_map_stride"), 4);
  EXPECT_EQ(config.at("adaptive_refresh"), 5);
}

// A run resumed at its checkpoint's end trains nothing: its last progress shows the checkpoint's loss
// and PSNR (they read 0 in `status` and the worker's gauges), and says where it began, so the worker's
// iteration counter counts only what it trained (found 2026-12-07).
TEST(Reconstruct, ARunResumedAtItsEndShowsItsCheckpointsLossAndPsnr) {
  testing::TempDir dir("reconstruct-resume-end");
  WriteSmallClip(dir / "clip");
  ReconstructOptions first = SmallRunOptions(dir / "clip", dir / "first");
  first.iterations = 12;
  Reconstruct(first, {});
  const nlohmann::json last = ReadJsonFile(dir / "first" / "metrics.json").at("curve").back();

  ReconstructOptions resumed = SmallRunOptions(dir / "clip", dir / "resumed");
  resumed.resume_from = (dir / "first" / "model" / "checkpoint.bin").string();
  resumed.iterations = 12;
  std::vector<Progress> training;
  ReconstructHooks hooks;
  hooks.on_progress = [&](const Progress& p) {
    if (p.phase.empty()) training.push_back(p);
  };
  Reconstruct(resumed, hooks);
  ASSERT_FALSE(training.empty());
  EXPECT_EQ(training.back().iteration, 12);
  EXPECT_EQ(training.back().first_iteration, 12);
  EXPECT_GT(training.back().train_psnr, 0.0);
  EXPECT_DOUBLE_EQ(training.back().train_psnr, last.at("train_psnr").get<double>());
  EXPECT_DOUBLE_EQ(training.back().loss, last.at("loss").get<double>());
}

}  // namespace
}  // namespace endorecon
