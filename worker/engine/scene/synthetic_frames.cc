#include "worker/engine/scene/synthetic_frames.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "common/error.h"
#include "worker/engine/scene/portable_random.h"
#include "worker/engine/scene/synthetic_files.h"  // ToByte (inline)

namespace endorecon::scene {
namespace {

constexpr double kSpecularHole = 0.35;  // stereo matching fails on highlights brighter than this

void PutRgb(std::vector<std::uint8_t>& image, std::size_t pixel, const std::array<float, 3>& rgb) {
  for (int c = 0; c < 3; ++c) image[pixel * 3 + c] = ToByte(rgb[c]);
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
// gamma curve is steepest there): σ about 3.3 levels of 255 at a stored 0.3, 2.5 at 0.7, times
// `scale` (SynthOptions::noise).
constexpr double kShot = 4e-4, kRead = 0.004;

std::array<float, 3> CameraNoise(const std::array<float, 3>& rgb, double scale, PortableRandom& random) {
  std::array<float, 3> out;
  for (int c = 0; c < 3; ++c) {
    const double linear = std::pow(std::clamp(double(rgb[c]), 0.0, 1.0), 2.2);
    const double sigma = scale * std::sqrt(kShot * linear + kRead * kRead);
    const double noisy = std::max(0.0, linear + sigma * random.Normal());
    out[c] = float(std::pow(noisy, 1.0 / 2.2));
  }
  return out;
}

void PunchHoles(std::vector<std::uint8_t>& depth, int w, int h, PortableRandom& random) {
  const int holes = 2 + static_cast<int>(random.Uniform(0, 3));
  for (int n = 0; n < holes; ++n) {
    const double cx = random.Uniform(0, w), cy = random.Uniform(0, h);
    const double radius = random.Uniform(0.02, 0.06) * w;
    for (int v = 0; v < h; ++v) {
      for (int u = 0; u < w; ++u) {
        if ((u + 0.5 - cx) * (u + 0.5 - cx) + (v + 0.5 - cy) * (v + 0.5 - cy) < radius * radius) {
          depth[static_cast<std::size_t>(v) * w + u] = 0;
        }
      }
    }
  }
}

Camera LeftCameraAt(const SyntheticScene& scene, const SynthOptions& options, int index) {
  Camera camera = scene.LeftCamera();
  camera.c2w = scene.LeftPose(FrameTime(options, index));
  return camera;
}

}  // namespace

void CheckSynthOptions(const SynthOptions& options) {
  if (options.frames < 1 || options.width < 1 || options.height < 1) {
    FailInvalid("synthetic clip: frames, width and height must be positive (got " +
                std::to_string(options.frames) + " frames of " + std::to_string(options.width) + "x" +
                std::to_string(options.height) + ")");
  }
  if (!options.texture.empty() &&
      (options.texture_width < 2 || options.texture_height < 2 ||
       options.texture.size() != std::size_t(options.texture_width) * options.texture_height * 3)) {
    FailInvalid("synthetic clip: the texture must be at least 2 x 2 RGB pixels (got " +
                std::to_string(options.texture_width) + " x " + std::to_string(options.texture_height) +
                ", " + std::to_string(options.texture.size()) + " bytes)");
  }
  if (!(options.motion >= 1 && options.motion <= 10) || !(options.flicker >= 0 && options.flicker < 1)) {
    FailInvalid("synthetic clip: motion must be in [1, 10] and flicker in [0, 1)");
  }
  if (!(options.noise >= 0 && options.noise <= 10)) {
    FailInvalid("synthetic clip: noise must be in [0, 10] (got " + std::to_string(options.noise) + ")");
  }
}

SyntheticFrame RenderSyntheticFrame(const SyntheticScene& scene, const SynthOptions& options, int index) {
  const SyntheticScene::State state = scene.At(FrameTime(options, index));
  const Camera camera = LeftCameraAt(scene, options, index);
  const int w = options.width, h = options.height;
  const std::size_t pixels = static_cast<std::size_t>(w) * h;
  SyntheticFrame frame;
  frame.rgb.resize(pixels * 3);
  frame.gt_rgb.resize(pixels * 3);
  if (options.stereo) frame.right_rgb.resize(pixels * 3);
  frame.depth.resize(pixels);
  frame.tool_mask.resize(pixels);
  frame.gt_depth.resize(pixels);
  PortableRandom random(StreamSeed(options.seed, static_cast<std::uint64_t>(index)));
  // Camera noise draws from its own stream, so the clip's other random parts stay as without it.
  PortableRandom noise(StreamSeed(StreamSeed(options.seed, 0x6e6f697365), static_cast<std::uint64_t>(index)));
  // The frame's exposure (flicker) scales what the scene sends, in gt/images too; then the camera's noise.
  const float gain =
      options.flicker > 0
          ? float(1 + options.flicker * PortableRandom(StreamSeed(StreamSeed(options.seed, 0x666c69636b),
                                                                  std::uint64_t(index)))
                                            .Uniform(-1, 1))
          : 1.0f;
  const auto lit = [gain](std::array<float, 3> rgb) {
    for (float& c : rgb) c *= gain;
    return rgb;
  };
  const auto seen = [&](const std::array<float, 3>& rgb) {
    return options.noise > 0 ? CameraNoise(lit(rgb), options.noise, noise) : lit(rgb);
  };
  const Eigen::Vector3d right_origin = camera.c2w.col(3) + scene.baseline() * camera.c2w.col(0);

  for (int v = 0; v < h; ++v) {
    double guess = 0, right_guess = 0;
    for (int u = 0; u < w; ++u) {
      const std::size_t pixel = static_cast<std::size_t>(v) * w + u;
      Eigen::Vector3d origin, direction;
      camera.Ray(u, v, origin, direction);
      const SceneHit hit = scene.TraceAlong(state, origin, direction, guess);
      guess = hit.tissue_depth;
      PutRgb(frame.rgb, pixel, seen(hit.rgb));
      PutRgb(frame.gt_rgb, pixel, lit(hit.tissue_rgb));
      frame.gt_depth[pixel] = static_cast<float>(hit.tissue_depth);
      frame.tool_mask[pixel] = hit.tool ? 255 : 0;
      const std::uint8_t noisy = NoisyDepth(hit.depth, random);
      frame.depth[pixel] = hit.specular > kSpecularHole ? 0 : noisy;
      if (options.stereo) {
        const SceneHit right_hit = scene.TraceAlong(state, right_origin, direction, right_guess);
        right_guess = right_hit.tissue_depth;
        PutRgb(frame.right_rgb, pixel, seen(right_hit.rgb));
      }
    }
  }
  PunchHoles(frame.depth, w, h, random);
  return frame;
}

Clip MakeSyntheticClip(const SynthOptions& options) {
  CheckSynthOptions(options);
  const SyntheticScene scene(options);
  const int n = options.frames;
  std::vector<SyntheticFrame> frames(static_cast<std::size_t>(n));
  tbb::parallel_for(0, n, [&](int index) { frames[index] = RenderSyntheticFrame(scene, options, index); });

  Clip clip;
  clip.source = "synthetic clip (in memory, seed " + std::to_string(options.seed) + ")";
  clip.width = options.width;
  clip.height = options.height;
  clip.near = scene.near();
  clip.far = scene.far();
  for (int i = 0; i < n; ++i) {
    SyntheticFrame& frame = frames[static_cast<std::size_t>(i)];
    clip.cameras.push_back(LeftCameraAt(scene, options, i));
    clip.times.push_back(n == 1 ? 0.f : static_cast<float>(i) / static_cast<float>(n - 1));
    clip.rgb.push_back(std::move(frame.rgb));
    clip.gt_rgb.push_back(std::move(frame.gt_rgb));
    clip.gt_depth.push_back(std::move(frame.gt_depth));
    // As the loader reads the files: depth in clip units (the 8-bit values, scale 1), masks 1 = tool.
    if (options.depth) clip.depth.emplace_back(frame.depth.begin(), frame.depth.end());
    if (options.tool) {
      for (auto& value : frame.tool_mask) value = value ? 1 : 0;
      clip.tool_mask.push_back(std::move(frame.tool_mask));
    }
    if (options.stereo) {
      clip.right_rgb.push_back(std::move(frame.right_rgb));
      Camera right = clip.cameras.back();
      right.c2w.col(3) += scene.baseline() * right.c2w.col(0);
      clip.right_cameras.push_back(right);
    }
  }
  clip.is_static = n == 1;
  return clip;
}

}  // namespace endorecon::scene
