// endorecon-worker synth: writes a synthetic clip with known ground truth (EndoNeRF layout + gt/), or
// with --object an object capture in the NeRF-synthetic layout (transforms.json, RGBA images).
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <filesystem>
#include <memory>
#include <system_error>

#include "common/cli_checks.h"
#include "common/error.h"
#include "worker/engine/scene/synthetic_clip.h"
#include "worker/engine/scene/synthetic_object.h"
#include "worker/runtime/commands.h"
#include "worker/runtime/synth_texture.h"

namespace endorecon::worker {

Command AddSynthCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand("synth", "write a synthetic clip with ground truth (EndoNeRF layout)");
  auto out = std::make_shared<std::string>();
  auto options = std::make_shared<scene::SynthOptions>();
  auto flags = std::make_shared<std::pair<bool, bool>>(false, false);  // --no-tool, --no-depth
  auto no_noise = std::make_shared<bool>(false);
  auto object = std::make_shared<bool>(false);
  auto backdrop = std::make_shared<bool>(false);
  auto texture = std::make_shared<std::string>();
  auto texture_frame = std::make_shared<int>(-1);
  cmd->add_option("out", *out, "output folder")->required();
  cmd->add_option("--frames", options->frames, "number of frames (views with --object; default there 100)")
      ->capture_default_str()
      ->check(CLI::Range(1, 100000));
  cmd->add_option("--width", options->width, "frame width (with --object default 200)")
      ->capture_default_str()
      ->check(CLI::Range(8, 8192));
  cmd->add_option("--height", options->height, "frame height (with --object default 200)")
      ->capture_default_str()
      ->check(CLI::Range(8, 8192));
  cmd->add_option("--seed", options->seed, "random seed")->capture_default_str()->check(AtLeastZero());
  cmd->add_flag("--static", options->static_scene, "nothing moves");
  cmd->add_flag("--no-tool", flags->first, "no tool, no masks/ folder");
  cmd->add_flag("--no-depth", flags->second, "no depth/ folder");
  auto* no_noise_flag = cmd->add_flag(
      "--no-noise", *no_noise,
      "images without camera noise (default: shot and read noise per channel, as a camera; gt/images "
      "stays noise-free); the same as --noise 0");
  cmd->add_option("--noise", options->noise,
                  "the camera noise's standard deviation times K (1: about 3 levels of 255 at mid grey; "
                  "the real laparoscopic recording in shared/data shows less than K = 0.1 gives, "
                  "docs/formats.md)")
      ->capture_default_str()
      ->check(Within(0.0, 10.0))
      ->excludes(no_noise_flag);
  cmd->add_flag("--stiff", options->stiff,
                "thin depth range, near-opaque surface, near-black tissue, saturated speculars");
  cmd->add_flag("--stereo", options->stereo, "also write the right eye (images_right/, stereo.json)");
  cmd->add_flag("--moving", options->moving,
                "the endoscope moves along a known path (poses in poses_bounds.npy)");
  cmd->add_flag("--recording", options->recording,
                "also write recording/: the raw stereo pair with lens distortion, its calibration, poses and "
                "checkerboard views (input for prepare and calibrate)");
  cmd->add_option("--texture", *texture,
                  "the tissue's albedo from a picture: an image file, or a frame of a video or image folder "
                  "(its centre, 70% of the shorter side), e.g. a real recording");
  cmd->add_option("--texture-frame", *texture_frame, "which frame of a video (default: the middle one)");
  cmd->add_option(
         "--motion", options->motion,
         "scale the tissue's motion: the pull (which drags the texture) K times as long, back and forth "
         "(1 + K) / 2 times, and the light circling the lens so the speculars move")
      ->capture_default_str()
      ->check(Within(1.0, 10.0));
  cmd->add_flag("--push", options->push, "the tool's tip presses a dent into the tissue that follows it");
  cmd->add_option("--flicker", options->flicker,
                  "each frame's exposure scaled by 1 + F u, u uniform in [-1, 1] (gt/images too)")
      ->capture_default_str()
      ->check(Within(0.0, 0.99));
  cmd->add_flag("--object", *object,
                "an object capture instead: cameras around a textured object at the origin, RGBA images on "
                "transparency, transforms.json as NeRF-synthetic (the endoscope options do not apply)");
  cmd->add_flag("--backdrop", *backdrop,
                "with --object: opaque images in front of a backdrop whose colour depends on the direction "
                "(train it with background \"learned\")");
  return [cmd, out, options, flags, no_noise, object, backdrop, texture, texture_frame] {
    if (*backdrop && !*object) FailInvalid("synth: --backdrop needs --object");
    if (std::error_code error;
        std::filesystem::exists(*out, error) && !std::filesystem::is_directory(*out, error))
      FailInvalid("synth: " + *out + " is a file; name the folder to write the clip into");
    if (*object) {
      scene::ObjectSynthOptions object_options;
      if (cmd->count("--frames") > 0) object_options.views = options->frames;
      if (cmd->count("--width") > 0) object_options.width = options->width;
      if (cmd->count("--height") > 0) object_options.height = options->height;
      object_options.seed = options->seed;
      object_options.backdrop = *backdrop;
      scene::WriteSyntheticObject(object_options, *out);
      spdlog::info("wrote synthetic object capture: {} ({} views, {}x{})", *out, object_options.views,
                   object_options.width, object_options.height);
      return 0;
    }
    // The recording's checkerboard views are for `calibrate`: at 64 x 48 its squares are ~4 px and no
    // view was found (96 x 72 calibrates at 0.13 px RMS; measured 2026-12-05).
    if (options->recording && (options->width < 96 || options->height < 72)) {
      FailInvalid("synth --recording: frames of " + std::to_string(options->width) + "x" +
                  std::to_string(options->height) +
                  " are too small for the recording's checkerboard to be found by calibrate; give at least "
                  "--width 96 --height 72");
    }
    if (!texture->empty()) LoadSynthTexture(*texture, *texture_frame, *options);
    options->tool = !flags->first;
    if (*no_noise) options->noise = 0;
    options->depth = !flags->second;
    scene::WriteSyntheticClip(*options, *out);
    spdlog::info("wrote synthetic clip: {} ({} frames, {}x{})", *out, options->frames, options->width,
                 options->height);
    return 0;
  };
}

}  // namespace endorecon::worker
