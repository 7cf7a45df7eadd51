// Small images streamed while a job runs, made from rendered frames with the exports' 8-bit
// conversion (quantize.h, NaN-safe).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "worker/engine/render/frame_renderer.h"

namespace endorecon::eval {

// 8-bit, row-major, `channels` 1 or 3.
struct Preview {
  std::string kind;  // "rgb", "depth" or "uncertainty"
  int frame = 0;
  int width = 0, height = 0, channels = 0;
  std::vector<std::uint8_t> pixels;
};

// The rendered colour of frame `index`.
Preview RgbPreview(const render::RenderedFrame& frame, int index);

// The total uncertainty as grey, scaled by the preview's own largest finite value (a preview shows
// where the uncertainty is, not how large it is; the results' heat maps carry the clip-wide scale).
// Non-finite values read as 0.
Preview UncertaintyPreview(const render::RenderedFrame& frame, int index);

}  // namespace endorecon::eval
