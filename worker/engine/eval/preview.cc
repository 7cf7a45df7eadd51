#include "worker/engine/eval/preview.h"

#include <algorithm>
#include <cmath>

#include "worker/engine/eval/quantize.h"

namespace endorecon::eval {

Preview RgbPreview(const render::RenderedFrame& frame, int index) {
  Preview preview{"rgb", index, frame.width, frame.height, 3, {}};
  preview.pixels.resize(frame.rgb.size());
  std::transform(frame.rgb.begin(), frame.rgb.end(), preview.pixels.begin(), ToByte);
  return preview;
}

Preview UncertaintyPreview(const render::RenderedFrame& frame, int index) {
  Preview preview{"uncertainty", index, frame.width, frame.height, 1, {}};
  float top = 0;
  for (float v : frame.uncertainty) top = std::isfinite(v) ? std::max(top, v) : top;
  preview.pixels.resize(frame.uncertainty.size());
  std::transform(frame.uncertainty.begin(), frame.uncertainty.end(), preview.pixels.begin(),
                 [top](float v) { return ToByte(std::isfinite(v) && top > 0 ? v / top : 0.0f); });
  return preview;
}

}  // namespace endorecon::eval
