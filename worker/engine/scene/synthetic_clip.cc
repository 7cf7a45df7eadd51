#include "worker/engine/scene/synthetic_clip.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include "common/error.h"
#include "worker/engine/scene/npy.h"
#include "worker/engine/scene/portable_random.h"
#include "worker/engine/scene/synthetic_files.h"
#include "worker/engine/scene/synthetic_recording.h"

namespace endorecon::scene {
namespace {

namespace fs = std::filesystem;

constexpr double kSpecularHole = 0.35;  // stereo matching fails on highlights brighter than this

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

// Observed z-depth plus truncated, depth-dependent noise, rounded to the 8-bit grid (1..255).
std::uint8_t NoisyDepth(double depth, PortableRandom& random) {
  const double sigma = 0.25 + 0.5 * (depth / 90) * (depth / 90);
  const double noisy = depth + sigma * std::clamp(random.Normal(), -3.0, 3.0);
  return static_cast<std::uint8_t>(std::clamp(std::lround(noisy), 1L, 255L));
}

// A camera's noise on a pixel's colour: in linear light (the stored value to the power 2.2) each
// channel gets independent Gaussian noise of variance kShot * signal + kRead^2 (shot noise and read
// noise), then goes back to stored values. Dark pixels are the noisiest in stored values (the
// gamma curve is steepest there): σ about 3.3 levels of 255 at a stored 0.3, 2.5 at 0.7.
constexpr double kShot = 4e-4, kRead = 0.004;

std::array<float, 3> CameraNoise(const std::array<float, 3>& rgb, PortableRandom& random) {
  std::array<float, 3> out;
  for (int c = 0; c < 3; ++c) {
    const double linear = std::pow(std::clamp(double(rgb[c]), 0.0, 1.0), 2.2);
    const double sigma = std::sqrt(kShot * linear + kRead * kRead);
    const double noisy = std::max(0.0, linear + sigma * random.Normal());
    out[c] = float(std::pow(noisy, 1.0 / 2.2));
  }
  return out;
}

void PunchHoles(cv::Mat& depth, PortableRandom& random) {
  const int holes = 2 + static_cast<int>(random.Uniform(0, 3));
  for (int h = 0; h < holes; ++h) {
    const double cx = random.Uniform(0, depth.cols), cy = random.Uniform(0, depth.rows);
    const double radius = random.Uniform(0.02, 0.06) * depth.cols;
    for (int v = 0; v < depth.rows; ++v) {
      for (int u = 0; u < depth.cols; ++u) {
        if ((u + 0.5 - cx) * (u + 0.5 - cx) + (v + 0.5 - cy) * (v + 0.5 - cy) < radius * radius) {
          depth.at<std::uint8_t>(v, u) = 0;
        }
      }
    }
  }
}

void WriteFrame(const SyntheticScene& scene, const SynthOptions& options, int index, const fs::path& out) {
  const double time = FrameTime(options, index);
  const SyntheticScene::State state = scene.At(time);
  Camera camera = scene.LeftCamera();
  camera.c2w = scene.LeftPose(time);
  const int w = options.width, h = options.height;
  cv::Mat rgb(h, w, CV_8UC3), gt_rgb(h, w, CV_8UC3), right(h, w, CV_8UC3), depth(h, w, CV_8UC1),
      mask(h, w, CV_8UC1);
  std::vector<float> gt_depth(static_cast<std::size_t>(w) * h);
  PortableRandom random(StreamSeed(options.seed, static_cast<std::uint64_t>(index)));
  // Camera noise draws from its own stream, so the clip's other random parts stay as without it.
  PortableRandom noise(StreamSeed(StreamSeed(options.seed, 0x6e6f697365), static_cast<std::uint64_t>(index)));
  // The frame's exposure (flicker) scales what the scene sends, in gt/images too; then the camera's noise.
  const float gain =
      options.flicker > 0
          ? float(1 + options.flicker *
                          PortableRandom(StreamSeed(StreamSeed(options.seed, 0x666c69636b), std::uint64_t(index)))
                              .Uniform(-1, 1))
          : 1.0f;
  const auto lit = [gain](std::array<float, 3> rgb) {
    for (float& c : rgb) c *= gain;
    return rgb;
  };
  const auto seen = [&](const std::array<float, 3>& rgb) {
    return options.noise ? CameraNoise(lit(rgb), noise) : lit(rgb);
  };
  const Eigen::Vector3d right_origin = camera.c2w.col(3) + scene.baseline() * camera.c2w.col(0);

  for (int v = 0; v < h; ++v) {
    double guess = 0, right_guess = 0;
    for (int u = 0; u < w; ++u) {
      Eigen::Vector3d origin, direction;
      camera.Ray(u, v, origin, direction);
      const SceneHit hit = scene.TraceAlong(state, origin, direction, guess);
      guess = hit.tissue_depth;
      PutRgb(rgb, u, v, seen(hit.rgb));
      PutRgb(gt_rgb, u, v, lit(hit.tissue_rgb));
      gt_depth[static_cast<std::size_t>(v) * w + u] = static_cast<float>(hit.tissue_depth);
      mask.at<std::uint8_t>(v, u) = hit.tool ? 255 : 0;
      const std::uint8_t noisy = NoisyDepth(hit.depth, random);
      depth.at<std::uint8_t>(v, u) = hit.specular > kSpecularHole ? 0 : noisy;
      if (options.stereo) {
        const SceneHit right_hit = scene.TraceAlong(state, right_origin, direction, right_guess);
        right_guess = right_hit.tissue_depth;
        PutRgb(right, u, v, seen(right_hit.rgb));
      }
    }
  }
  PunchHoles(depth, random);

  const std::string name = FrameName(index), png = name + ".png";
  WritePng(out / "images" / png, rgb);
  WritePng(out / "gt/images" / png, gt_rgb);
  WriteNpyFloat32(out / "gt/depth" / (name + ".npy"), gt_depth.data(),
                  {static_cast<std::size_t>(h), static_cast<std::size_t>(w)});
  if (options.depth) WritePng(out / "depth" / png, depth);
  if (options.tool) WritePng(out / "masks" / png, mask);
  if (options.stereo) WritePng(out / "images_right" / png, right);
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
  if (options.frames < 1 || options.width < 1 || options.height < 1) {
    FailInvalid("synthetic clip: frames, width and height must be positive (got " +
                std::to_string(options.frames) + " frames of " + std::to_string(options.width) + "x" +
                std::to_string(options.height) + ")");
  }
  if (!options.texture.empty() &&
      (options.texture_width < 2 || options.texture_height < 2 ||
       options.texture.size() != std::size_t(options.texture_width) * options.texture_height * 3)) {
    FailInvalid("synthetic clip: the texture must be at least 2 x 2 RGB pixels (got " +
                std::to_string(options.texture_width) + " x " + std::to_string(options.texture_height) + ", " +
                std::to_string(options.texture.size()) + " bytes)");
  }
  if (!(options.motion >= 1 && options.motion <= 10) || !(options.flicker >= 0 && options.flicker < 1)) {
    FailInvalid("synthetic clip: motion must be in [1, 10] and flicker in [0, 1)");
  }
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
