#include "worker/engine/train/ray_sampler.h"

#include <algorithm>

#include "common/error.h"
#include "worker/engine/base/counter_rng.h"

namespace endorecon::train {

RaySampler::RaySampler(const scene::Clip& clip, std::vector<int> frames) : clip_(clip) {
  const std::size_t pixels = std::size_t(clip.width) * clip.height;
  if (clip.has_masks()) {
    std::vector<int> tool_count(pixels, 0);
    for (int f : frames) {
      for (std::size_t p = 0; p < pixels; ++p) tool_count[p] += clip.tool_mask[f][p];
    }
    const int most = *std::max_element(tool_count.begin(), tool_count.end());
    occlusion_weight_.resize(pixels);
    for (std::size_t p = 0; p < pixels; ++p) {
      occlusion_weight_[p] = 1.0f + (most > 0 ? float(tool_count[p]) / float(most) : 0.0f);
    }
    std::erase_if(frames, [&](int f) {
      const auto& mask = clip.tool_mask[f];
      return std::all_of(mask.begin(), mask.end(), [](std::uint8_t m) { return m != 0; });
    });
  }
  if (frames.empty())
    FailInvalid(clip.source + ": no training frame has a tissue pixel (every pixel is tool)");
  frames_ = std::move(frames);
}

float RaySampler::Weight(int frame, int pixel) const {
  if (occlusion_weight_.empty()) return 1.0f;
  return clip_.tool_mask[frame][pixel] ? 0.0f : occlusion_weight_[pixel];
}

RayPick RaySampler::Pick(std::uint64_t seed, std::uint64_t stream) const {
  const base::CounterRng<double> uniform(seed, stream);
  const int pixels = clip_.width * clip_.height;
  RayPick pick;
  // Every frame kept has a tissue pixel, so acceptance is at least 1 / (2 * pixels) per draw; in
  // practice tissue covers most of a frame and a few draws suffice.
  for (unsigned draw = 0;; draw += 3) {
    pick.frame = frames_[std::min<int>(int(uniform(draw) * frames_.size()), int(frames_.size()) - 1)];
    pick.pixel = std::min(int(uniform(draw + 1) * pixels), pixels - 1);
    if (uniform(draw + 2) * 2.0 < Weight(pick.frame, pick.pixel)) return pick;
  }
}

}  // namespace endorecon::train
