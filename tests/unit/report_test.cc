// report.html as written at the end of a reconstruction: what its data block holds, for a finished and
// a cancelled run, and the errors for a folder that is not a results folder. (The page itself runs in
// a browser in tests/e2e/report_page_test.cc.)
#include "worker/engine/eval/report.h"

#include <gtest/gtest.h>

#include <atomic>
#include <fstream>
#include <memory>

#include "common/error.h"
#include "common/json_file.h"
#include "tests/unit/clip_fixture.h"
#include "tests/unit/report_data.h"
#include "tests/unit/temp_dir.h"
#include "worker/engine/eval/surface_grid.h"
#include "worker/engine/reconstruct.h"
#include "worker/engine/scene/synthetic_clip.h"

namespace endorecon::eval {
namespace {

namespace fs = std::filesystem;

class ReportTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new testing::TempDir("report");
    scene::SynthOptions synth;
    synth.frames = 8;
    synth.width = 48;
    synth.height = 40;
    scene::WriteSyntheticClip(synth, dir_->path() / "clip");
  }
  static void TearDownTestSuite() {
    delete dir_;
    dir_ = nullptr;
  }
  static ReconstructOptions Options(const std::string& out) {
    ReconstructOptions options;
    options.clip_dir = (dir_->path() / "clip").string();
    options.out_dir = (dir_->path() / out).string();
    options.config = {
        {"rays_per_batch", 256}, {"depth_refine_every", 0}, {"occupancy_resolution", 16}, {"mc_passes", 2}};
    options.iterations = 20;
    options.holdout = 4;
    options.threads = 2;
    return options;
  }
  static inline testing::TempDir* dir_ = nullptr;
};

TEST_F(ReportTest, AReconstructionsPageHoldsEveryFrameItsMetricsAndItsRun) {
  const ReconstructOptions options = Options("out");
  Reconstruct(options, {});
  const fs::path out = options.out_dir;
  const auto data = testing::ReportData(out / "report.html");
  ASSERT_TRUE(data.is_object()) << "no data block in report.html";
  EXPECT_EQ(data["kind"], "reconstruction");
  EXPECT_EQ(data["title"], "clip");
  EXPECT_EQ(data["metrics"], ReadJsonFile(out / "metrics.json"));
  EXPECT_EQ(data["config"], ReadJsonFile(out / "config.json"));
  EXPECT_EQ(data["run"]["device"], "CPU, 2 threads");
  EXPECT_EQ(data["run"]["version"].get<std::string>().rfind("0.1.0", 0), 0u) << data["run"]["version"];
  EXPECT_GT(data["run"]["machine"]["logical_cores"].get<int>(), 0);

  const auto& frames = data["frames"];
  EXPECT_EQ(frames["count"], 8);
  EXPECT_EQ(frames["times"].size(), 8u);
  EXPECT_EQ(frames["source_width"], 48);
  for (const char* layer : {"input", "rendered", "depth", "uncertainty", "model", "error", "tool"}) {
    ASSERT_EQ(frames[layer].size(), 8u) << layer;
    EXPECT_EQ(frames[layer][3].get<std::string>().rfind("data:image/", 0), 0u) << layer;
  }
  EXPECT_EQ(data["scales"]["uncertainty"]["range"],
            data["metrics"]["uncertainty_maps"]["heatmap_scale"]["uncertainty"]);
  // The score's scale is shown divided by lambda (1e12 by default): as the colour's variance.
  EXPECT_DOUBLE_EQ(data["scales"]["uncertainty"]["factor"].get<double>(),
                   1.0 / data["metrics"]["uncertainty_maps"]["lambda"].get<double>());
  EXPECT_EQ(data["scales"]["uncertainty"]["unit"], "colour variance");
  EXPECT_EQ(data["scales"]["error"]["range"], data["metrics"]["uncertainty_maps"]["heatmap_scale"]["error"]);
  EXPECT_EQ(data["scales"]["model"]["range"], data["metrics"]["uncertainty_maps"]["heatmap_scale"]["model"]);
  const auto depth_range = data["scales"]["depth"]["range"];
  EXPECT_GT(depth_range[1].get<double>(), depth_range[0].get<double>());
  EXPECT_GT(depth_range[0].get<double>(), 0.0);

  const auto& surface = data["surface"];
  ASSERT_EQ(surface["frames"].size(), 8u);
  EXPECT_EQ(surface["stride"], SurfaceStride(48, 40, 8, 600000));
  const auto& grid = surface["frames"][0]["grid"];
  const std::size_t points = grid[0].get<std::size_t>() * grid[1].get<std::size_t>();
  EXPECT_EQ(surface["frames"][0]["depth"].get<std::string>().size(), 4 * ((2 * points + 2) / 3));
  EXPECT_EQ(surface["frames"][0]["camera"]["width"], 48);
  EXPECT_EQ(surface["frames"][0]["uncertainty"].get<std::string>().size(), 4 * ((points + 2) / 3));
  EXPECT_EQ(surface["frames"][0]["model"].get<std::string>().size(), 4 * ((points + 2) / 3));
  EXPECT_EQ(surface["view"]["eye"].size(), 3u);

  // A service job's page is titled by the job's name (config.json "title"): its clip folder is
  // "clip" for every job, and every job's page read "endorecon report: clip" (found 2026-12-06).
  nlohmann::json config = ReadJsonFile(out / "config.json");
  config["title"] = "liver, case 12";
  std::ofstream(out / "config.json") << config.dump(2);
  WriteReport(out);
  EXPECT_EQ(testing::ReportData(out / "report.html")["title"], "liver, case 12");
  config["title"] = 12;  // no name: the clip folder's, as before
  std::ofstream(out / "config.json") << config.dump(2);
  WriteReport(out);
  EXPECT_EQ(testing::ReportData(out / "report.html")["title"], "clip");
}

// A run of some of a clip folder's frames (--frames) says which in config.json, and its page, drawn
// again from the results, shows those frames.
TEST_F(ReportTest, ARunOfPickedFramesRecordsThemAndItsPageShowsThem) {
  ReconstructOptions options = Options("picked");
  options.frames = ParseFrameRange("1:8:2");
  options.iterations = 5;
  Reconstruct(options, {});
  const fs::path out = options.out_dir;
  EXPECT_EQ(ReadJsonFile(out / "config.json")["frames"], "1:8:2");
  EXPECT_EQ(ReadJsonFile(out / "metrics.json")["train"]["frames"].size() +
                ReadJsonFile(out / "metrics.json")["heldout"]["frames"].size(),
            4u);
  WriteReport(out);
  const auto data = testing::ReportData(out / "report.html");
  EXPECT_EQ(data["frames"]["count"], 4);
  EXPECT_EQ(data["frames"]["input"].size(), 4u);
}

// A kept clip of a recording reconstructed with --frames: the page showed the time of the frame at the
// picked frame's index ("frame 2 / 2 ... 0.80 s into the recording" for one recorded at 9.6 s; found
// 2026-12-07). Each picked frame keeps its own time.
TEST_F(ReportTest, PickedFramesOfARecordingShowTheirOwnTimes) {
  const fs::path clip = dir_->path() / "clip-of-a-recording";
  fs::copy(dir_->path() / "clip", clip, fs::copy_options::recursive);
  testing::WriteBytes(clip / "recording.json",
                      R"({"source": "endo.dcm", "times_s": [0.0, 0.4, 0.8, 1.2, 1.6, 2.0, 2.4, 2.8]})");
  ReconstructOptions options = Options("picked-recording");
  options.clip_dir = clip.string();
  options.frames = ParseFrameRange("1:8:3");
  options.iterations = 3;
  Reconstruct(options, {});
  const auto data = testing::ReportData(fs::path(options.out_dir) / "report.html");
  EXPECT_EQ(data["recording"]["times_s"], (nlohmann::json{0.4, 1.6, 2.8}));
}

TEST_F(ReportTest, ACancelledRunsPageHasNoFramesButTheRest) {
  const ReconstructOptions options = Options("cancelled");
  ReconstructHooks hooks;
  // A stop asked while the clip loads ends the run without results (CANCELLED); asked once the 8
  // frames are loaded (the load asks once a frame), the run ends cancelled with its page.
  hooks.should_stop = [] { return true; };
  const std::string message =
      testing::ErrorFrom([&] { Reconstruct(Options("cancelled-loading"), hooks); }, ErrorCode::kCancelled);
  EXPECT_NE(message.find("the clip's load was stopped"), std::string::npos) << message;
  EXPECT_FALSE(fs::exists(dir_->path() / "cancelled-loading" / "report.html"));
  auto asked = std::make_shared<std::atomic<int>>(0);
  hooks.should_stop = [asked] { return ++*asked > 8; };
  ASSERT_TRUE(Reconstruct(options, hooks).cancelled);
  const auto data = testing::ReportData(fs::path(options.out_dir) / "report.html");
  ASSERT_TRUE(data.is_object());
  EXPECT_TRUE(data["metrics"]["cancelled"].get<bool>());
  // The optical flow that starts the deformation is skipped once a stop is asked for.
  EXPECT_NE(data["metrics"]["deformation_start"].dump().find("not fitted yet"), std::string::npos)
      << data["metrics"]["deformation_start"].dump();
  EXPECT_FALSE(data.contains("frames"));
  EXPECT_FALSE(data.contains("surface"));
}

TEST_F(ReportTest, AFolderThatHoldsNoResultsIsRefusedByName) {
  testing::TempDir empty("report-empty");
  try {
    WriteReport(empty.path());
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
    EXPECT_NE(std::string(e.what()).find(empty.path().string()), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("metrics.json"), std::string::npos) << e.what();
  }
  testing::WriteBytes(empty / "metrics.json", "{}");
  testing::WriteBytes(empty / "config.json", "{}");
  EXPECT_THROW(WriteReport(empty.path()), Error) << "config.json names no clip";
  EXPECT_FALSE(fs::exists(empty / "report.html"));
}

}  // namespace
}  // namespace endorecon::eval
