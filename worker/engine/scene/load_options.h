// What a clip loader may accept, set by the caller (the reconstruct command, the service's limits).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>

#include "common/prepare_flags.h"

namespace endorecon::scene {

struct LoadOptions {
  std::size_t max_pixels_per_frame = std::size_t{4096} * 4096;  // larger frames: INVALID_ARGUMENT
  bool force_static = false;  // mark the clip static (one time for all frames) whatever its layout says
  // The clip folder's frames to load (START:END:STEP of its own order; default all): the clip is then
  // as if cut to them by hand, an EndoNeRF clip's times spread over them again, a transforms.json
  // clip's own times kept. None selected: INVALID_ARGUMENT.
  FrameRange frames;
  // The colour transparent pixels of RGBA images are composited onto (RGB): NeRF-synthetic's white
  // unless the run's background is black (train_config.h "background").
  std::array<std::uint8_t, 3> alpha_background = {255, 255, 255};
  // Asked between frames: true stops the load with Error(kCancelled) (a job cancelled while its clip
  // loads waited for the whole load). Empty: never.
  std::function<bool()> should_stop;
  // Bring near/far to the depth priors where they are far looser or cut them off
  // (scene/depth_bounds.h; the training key fit_depth_bounds).
  bool fit_depth_bounds = true;
  // The memory the run may take (bytes; 0: unchecked), and what it keeps per pixel of the clip beside
  // the decoded frames (training's and evaluation's state, reconstruct.cc), with depth priors that
  // much and run_bytes_per_depth_pixel more: a clip that needs more is refused before a frame is
  // decoded, Error(kResourceExhausted).
  std::uint64_t memory_bytes = 0;
  double run_bytes_per_pixel = 0;
  double run_bytes_per_depth_pixel = 0;
  // Decoded bytes a pixel the clip loads beside its frames' files: LoadClip's, for a gt/ folder.
  double extra_bytes_per_pixel = 0;
};

}  // namespace endorecon::scene
