#include "worker/engine/scene/synthetic_clip.h"

#include <tbb/parallel_for.h>

#include <nlohmann/json.hpp>

#include "common/error.h"
#include "common/npy.h"
#include "worker/engine/scene/synthetic_files.h"
#include "worker/engine/scene/synthetic_frames.h"
#include "worker/engine/scene/synthetic_recording.h"

namespace endorecon::scene {
namespace {

namespace fs = std::filesystem;

nlohmann::json OptionsJson(const SynthOptions& o) {
  return {{"frames", o.frames}, {"width", o.width},         {"height", o.height},
          {"seed", o.seed},     {"static", o.static_scene}, {"tool", o.tool},
          {"depth", o.depth},   {"stiff", o.stiff},         {"stereo", o.stereo},
          {"moving", o.moving}, {"recording", o.recording}, {"checkerboard_views", o.checkerboard_views},
          {"noise", o.noise},   {"texture", o.texture_source}, {"motion", o.motion},
          {"push", o.push},     {"flicker", o.flicker}};
}

void PrepareFolder(const fs::path& out, const SynthOptions& options) {
  ClearSyntheticFolder(out);
  for (const char* dir : {"images", "gt/images", "gt/depth"}) fs::create_directories(out / dir);
  if (options.depth) fs::create_directories(out / "depth");
  if (options.tool) fs::create_directories(out / "masks");
  if (options.stereo) fs::create_directories(out / "images_right");
}

void WriteFrame(const SyntheticScene& scene, const SynthOptions& options, int index, const fs::path& out) {
  SyntheticFrame frame = RenderSyntheticFrame(scene, options, index);
  const int w = options.width, h = options.height;
  const std::string name = FrameName(index), png = name + ".png";
  WriteRgbPng(out / "images" / png, frame.rgb.data(), w, h, 3);
  WriteRgbPng(out / "gt/images" / png, frame.gt_rgb.data(), w, h, 3);
  WriteNpyFloat32(out / "gt/depth" / (name + ".npy"), frame.gt_depth.data(),
                  {static_cast<std::size_t>(h), static_cast<std::size_t>(w)});
  if (options.depth) WriteRgbPng(out / "depth" / png, frame.depth.data(), w, h, 1);
  if (options.tool) WriteRgbPng(out / "masks" / png, frame.tool_mask.data(), w, h, 1);
  if (options.stereo) WriteRgbPng(out / "images_right" / png, frame.right_rgb.data(), w, h, 3);
}

// EndoNeRF rows: the OpenGL pose [right, up, back | t] stored in LLFF's [down, right, back | t] order.
void WritePoses(const SyntheticScene& scene, const SynthOptions& options, const fs::path& path) {
  const double hwf[3] = {static_cast<double>(options.height), static_cast<double>(options.width),
                         scene.LeftCamera().fx};
  std::vector<double> rows;
  for (int i = 0; i < options.frames; ++i) {
    const Eigen::Matrix<double, 3, 4> pose = scene.LeftPose(FrameTime(options, i));
    for (int r = 0; r < 3; ++r) {
      // 0.0 - x keeps an identity's zeros positive (-0.0 would change the file's bytes).
      rows.insert(rows.end(), {0.0 - pose(r, 1), pose(r, 0), pose(r, 2), pose(r, 3), hwf[r]});
    }
    rows.insert(rows.end(), {scene.near(), scene.far()});
  }
  WriteNpyFloat64(path, rows.data(), {static_cast<std::size_t>(options.frames), 17});
}

}  // namespace

void WriteSyntheticClip(const SynthOptions& options, const fs::path& out) {
  CheckSynthOptions(options);
  PrepareFolder(out, options);
  WriteText(out / "synth.json", OptionsJson(options).dump(2) + "\n");
  const SyntheticScene scene(options);
  WritePoses(scene, options, out / "poses_bounds.npy");
  if (options.stereo)
    WriteText(out / "stereo.json", nlohmann::json{{"baseline", scene.baseline()}}.dump() + "\n");
  tbb::parallel_for(0, options.frames, [&](int index) { WriteFrame(scene, options, index, out); });
  if (options.recording) WriteSyntheticRecording(scene, options, out / "recording");
}

}  // namespace endorecon::scene
