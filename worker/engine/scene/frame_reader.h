// Reading the per-frame files of a clip (colour, depth, masks, right eye) into a Clip, with the
// checks every layout shares: readable files, one frame size, masks of 0/255, finite depth.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "common/clip_files.h"
#include "worker/engine/scene/clip.h"
#include "worker/engine/scene/load_options.h"

namespace endorecon::scene {

struct FrameReadOptions {
  double depth_scale = 1.0;       // clip units per raw depth value (integer or float files)
  std::uint8_t tool_value = 255;  // the mask value that marks the tool (the other allowed value: 255 - this)
  std::size_t max_pixels_per_frame = std::size_t{4096} * 4096;
  std::uint64_t memory_bytes = 0;                                  // LoadOptions'
  double run_bytes_per_pixel = 0;                                  // LoadOptions'
  double run_bytes_per_depth_pixel = 0;                            // LoadOptions'
  double extra_bytes_per_pixel = 0;                                // LoadOptions'
  std::array<std::uint8_t, 3> alpha_background = {255, 255, 255};  // what transparent pixels lie on
  std::function<bool()> should_stop;                               // LoadOptions' (load_options.h)
};

// The options a loader reads its frames with: the fields marked LoadOptions' taken from `options`,
// the rest at their defaults.
FrameReadOptions FrameReadOptionsOf(const LoadOptions& options);

// An image file as 8-bit RGB, row-major, top row first.
struct RgbImage {
  int width = 0, height = 0;
  std::vector<std::uint8_t> rgb;  // width * height * 3
  bool transparent = false;       // the file had an alpha channel and some pixel was not opaque
};

// Decodes an 8- or 16-bit grey, RGB or RGBA image; RGBA is composited onto `background` (straight
// alpha, as NeRF-synthetic captures store objects on transparency). Throws FailInvalid naming the
// file when it is missing, unreadable or truncated, or of an unsupported kind.
RgbImage ReadRgbImage(const std::filesystem::path& path,
                      const std::array<std::uint8_t, 3>& background = {255, 255, 255});

// Depth maps: single-channel 8-, 16-bit or float images, or .npy arrays of shape (H, W). Raw values
// times FrameReadOptions::depth_scale are clip units; 0 means unknown.

// Reads every frame into clip.rgb / depth / tool_mask / eval_mask / right_rgb (a part whose path is
// empty in the first frame stays empty and must be empty in all); clip.transparent is set when some
// colour image had transparent pixels (composited onto options.alpha_background). Every file must have the
// size clip.width x clip.height; when that is 0x0 the first image sets it. Throws the error of the lowest
// failing frame; Error(kInvalidArgument) for frames over options.max_pixels_per_frame, and
// Error(kResourceExhausted), before any frame is decoded, for a clip over options.memory_bytes.
void ReadFrames(const std::vector<FrameFiles>& frames, const FrameReadOptions& options, Clip& clip);

}  // namespace endorecon::scene
