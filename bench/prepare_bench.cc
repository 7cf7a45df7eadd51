// Preparation of raw stereo recordings (issue 16): frames per second of `prepare` at 640x512 and
// 1280x1024 on the synthetic rig's recording (lens distortion, rotated eyes, a tool, masks), the
// depth error against time of each depth option there, `calibrate` and `--estimate-poses` against
// the rig's truth (640x512), and optionally the reconstruction target:
// held-out PSNR of a clip prepared from the synthetic stereo pair against the same clip with the
// synthetic generator's own depth, each trained for the same time.
//   prepare_bench [--out DIR] [--frames N] [--sizes 640x512,1280x1024] [--reconstruct SECONDS]
//                 [--reconstruct-size WxH] [--reconstruct-frames N]
#include <CLI/CLI.hpp>
#include <Eigen/Geometry>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "tests/unit/synthetic_recording_fixture.h"
#include "worker/engine/reconstruct.h"
#include "worker/engine/scene/clip_loader.h"
#include "worker/prepare/checkerboard_calibration.h"

namespace {

namespace fs = std::filesystem;
using endorecon::prepare::DepthOptions;

struct Row {
  std::string name;
  DepthOptions depth;
};

std::vector<Row> DepthRows() {
  std::vector<Row> rows;
  for (const bool eight : {false, true}) {
    for (const bool refine : {false, true}) {
      DepthOptions d;
      d.eight_paths = eight;
      d.refine = refine;
      rows.push_back({std::string(eight ? "8-path" : "3-way") + (refine ? " + refine" : ""), d});
    }
  }
  return rows;
}

Eigen::Matrix4d Homogeneous(const Eigen::Matrix<double, 3, 4>& pose) {
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m.topRows<3>() = pose;
  return m;
}

// --estimate-poses on the moving endoscope (static tissue, light at the tip) against its path.
void MeasurePoses(const fs::path& root, int width, int height, int frames) {
  endorecon::scene::SynthOptions synth = endorecon::testing::RecordingOptions(width, height, frames);
  synth.moving = true;
  synth.static_scene = true;
  const fs::path dir = root / "poses";
  endorecon::scene::WriteSyntheticClip(synth, dir / "synth");
  endorecon::prepare::PrepareOptions options =
      endorecon::testing::RecordingPrepareOptions(dir / "synth", dir / "clip");
  options.estimate_poses = true;
  options.depth.eight_paths = true;  // what --estimate-poses chooses by default
  const auto summary = endorecon::prepare::PrepareClip(options);
  const auto report = endorecon::testing::ReadJson(dir / "clip/prepare.json");
  const auto clip = endorecon::scene::LoadClip(dir / "clip");
  const endorecon::scene::SyntheticScene scene(synth);
  const Eigen::Matrix4d first = Homogeneous(endorecon::testing::TruthCamera(scene, synth, report, 0).c2w);
  double length = 0, translation = 0, degrees = 0;
  Eigen::Vector3d previous = Eigen::Vector3d::Zero();
  for (int f = 0; f < clip.frame_count(); ++f) {
    const Eigen::Matrix4d truth =
        first.inverse() * Homogeneous(endorecon::testing::TruthCamera(scene, synth, report, f).c2w);
    const Eigen::Matrix4d estimate = Homogeneous(clip.cameras[f].c2w);
    length += (truth.topRightCorner<3, 1>() - previous).norm();
    previous = truth.topRightCorner<3, 1>();
    translation =
        std::max(translation, (estimate.topRightCorner<3, 1>() - truth.topRightCorner<3, 1>()).norm());
    degrees = std::max(
        degrees,
        Eigen::AngleAxisd(estimate.topLeftCorner<3, 3>().transpose() * truth.topLeftCorner<3, 3>()).angle() *
            180 / M_PI);
  }
  std::printf(
      "poses at %dx%d, %d frames: worst translation %.3f (%.2f%% of the %.2f-unit path), worst rotation "
      "%.3f deg, reprojection RMS %.3f px, %zu dropped\n",
      width, height, frames, translation, 100 * translation / length, length, degrees,
      summary.pose_reprojection.rms, summary.dropped.size());
}

// `calibrate` on the rig's 24 checkerboard views, and the true rig's rows rectified with the estimate.
void MeasureCalibration(const fs::path& root, int width, int height) {
  const endorecon::scene::SynthOptions synth = endorecon::testing::RecordingOptions(width, height, 1, 24);
  const fs::path dir = root / "calibration";
  endorecon::scene::WriteSyntheticClip(synth, dir / "synth");
  endorecon::prepare::CheckerboardOptions board;
  board.inner_corners = {endorecon::scene::kCheckerboardColumns, endorecon::scene::kCheckerboardRows};
  board.square = endorecon::scene::kCheckerboardSquare;
  const auto result =
      endorecon::prepare::CalibrateFromCheckerboard({endorecon::prepare::StereoLayout::kTwoSources,
                                                     dir / "synth/recording/checkerboard/left",
                                                     dir / "synth/recording/checkerboard/right",
                                                     {}},
                                                    board);
  const auto truth = endorecon::testing::SyntheticCalibration(synth);
  const auto [epipolar, projection] = endorecon::testing::EpipolarAndProjectionError(
      truth, endorecon::prepare::StereoRectifier(result.calibration, {}));
  const auto [exact, exact_projection] =
      endorecon::testing::EpipolarAndProjectionError(truth, endorecon::prepare::StereoRectifier(truth, {}));
  std::printf(
      "calibration at %dx%d: %d views, RMS reprojection %.3f px, baseline %.4f (true %.4f), fx %.2f "
      "(true %.2f); worst epipolar error over the view: %.3f px with the estimate, %.2g px with the truth\n",
      width, height, result.views_used, result.rms_px, result.calibration.baseline(), truth.baseline(),
      result.calibration.k1(0, 0), truth.k1(0, 0), epipolar, exact);
}

void MeasureSize(const fs::path& root, int width, int height, int frames) {
  const endorecon::scene::SynthOptions synth = endorecon::testing::RecordingOptions(width, height, frames);
  const fs::path dir = root / (std::to_string(width) + "x" + std::to_string(height));
  const auto t0 = std::chrono::steady_clock::now();
  endorecon::scene::WriteSyntheticClip(synth, dir / "synth");
  std::printf("%dx%d: %d frames rendered in %.1f s\n", width, height, frames,
              std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  const endorecon::scene::SyntheticScene scene(synth);
  std::printf("%-26s %10s %10s %10s %10s %12s %12s\n", "depth option", "frames/s", "RMSE", "MAE",
              "RMSE/range", "valid(seen)", "valid(all)");
  for (const Row& row : DepthRows()) {
    endorecon::prepare::PrepareOptions options =
        endorecon::testing::RecordingPrepareOptions(dir / "synth", dir / "clip");
    options.depth = row.depth;
    const auto summary = endorecon::prepare::PrepareClip(options);
    const auto report = endorecon::testing::ReadJson(dir / "clip/prepare.json");
    const auto score =
        endorecon::testing::ScoreDepth(scene, synth, endorecon::scene::LoadClip(dir / "clip"), report);
    std::printf("%-26s %10.2f %10.3f %10.3f %9.2f%% %11.1f%% %11.1f%%\n", row.name.c_str(),
                summary.frames / summary.seconds, score.rmse, score.mae, 100 * score.rmse / (130 - 40),
                100 * score.valid_visible_share(), 100 * score.valid_share());
    std::fflush(stdout);
  }
}

// The synthetic stereo pair as it is (rectified, no distortion) prepared with --rectified: the
// same images as the synthetic clip, with stereo depth instead of the generator's own.
void MeasureReconstruction(const fs::path& root, int width, int height, int frames, double seconds) {
  endorecon::scene::SynthOptions synth;
  synth.width = width;
  synth.height = height;
  synth.frames = frames;
  synth.stereo = true;
  const fs::path dir = root / "reconstruction";
  endorecon::scene::WriteSyntheticClip(synth, dir / "synth");
  endorecon::prepare::PrepareOptions options;
  options.recording = {
      endorecon::prepare::StereoLayout::kTwoSources, dir / "synth/images", dir / "synth/images_right", {}};
  options.rectified = true;
  options.focal = endorecon::scene::SyntheticScene(synth).LeftCamera().fx;
  options.baseline = 5;
  options.masks = dir / "synth/masks";
  options.out = dir / "prepared";
  const auto summary = endorecon::prepare::PrepareClip(options);
  fs::copy(dir / "synth/gt", dir / "prepared/gt", fs::copy_options::recursive);
  std::printf("reconstruction at %dx%d, %d frames, %.0f s of training each (every 8th frame held out):\n",
              width, height, frames, seconds);
  std::printf("  prepared clip: depth coverage %.1f%%\n", 100 * summary.depth_coverage);
  for (const char* clip : {"synth", "prepared"}) {
    endorecon::ReconstructOptions run;
    run.clip_dir = (dir / clip).string();
    run.out_dir = (dir / (std::string(clip) + "-result")).string();
    run.time_budget_s = seconds;
    run.holdout = 8;
    const endorecon::ReconstructSummary result = endorecon::Reconstruct(run, {});
    std::printf("  %-9s depth: held-out tissue PSNR %.2f dB (%d iterations)\n",
                std::string(clip) == "synth" ? "generator's" : "stereo", result.heldout_psnr,
                result.iterations);
    std::fflush(stdout);
  }
}

std::vector<std::pair<int, int>> ParseSizes(const std::string& text) {
  std::vector<std::pair<int, int>> sizes;
  std::stringstream list(text);
  std::string item;
  while (std::getline(list, item, ',')) {
    const auto size = endorecon::ParseFrameSize(item);
    sizes.emplace_back(size.width, size.height);
  }
  return sizes;
}

}  // namespace

int main(int argc, char** argv) {
  std::string out = "/tmp/endorecon-prepare-bench", sizes = "640x512,1280x1024", reconstruct_size = "320x256";
  int frames = 8, reconstruct_frames = 24;
  double reconstruct = 0;
  CLI::App app{"prepare_bench: preparing raw stereo recordings, against the synthetic truth"};
  app.add_option("--out", out, "scratch folder (emptied first)")->capture_default_str();
  app.add_option("--frames", frames, "frames per recording")->capture_default_str();
  app.add_option("--sizes", sizes, "recording sizes, WxH,...")->capture_default_str();
  app.add_option("--reconstruct", reconstruct, "also reconstruct a prepared clip for S seconds (0: no)")
      ->capture_default_str();
  app.add_option("--reconstruct-size", reconstruct_size, "its size, WxH")->capture_default_str();
  app.add_option("--reconstruct-frames", reconstruct_frames, "its frames")->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  fs::remove_all(out);
  for (const auto& [width, height] : ParseSizes(sizes)) MeasureSize(out, width, height, frames);
  MeasureCalibration(out, 640, 512);
  MeasurePoses(out, 640, 512, 12);
  if (reconstruct > 0) {
    const auto size = endorecon::ParseFrameSize(reconstruct_size);
    MeasureReconstruction(out, size.width, size.height, reconstruct_frames, reconstruct);
  }
  fs::remove_all(out);
  return 0;
}
