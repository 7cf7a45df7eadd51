#include "worker/engine/train/ray_sampler.h"

#include <algorithm>

#include "common/error.h"

namespace endorecon::train {

RaySampler::RaySampler(const scene::Clip& clip, std::vector<int> frames) {
  const std::size_t pixels = std::size_t(clip.width) * clip.height;
  if (clip.has_masks()) {
    std::vector<int> tool_count(pixels, 0);
    for (int f : frames) {
      for (std::size_t p = 0; p < pixels; ++p) tool_count[p] += clip.tool_mask[f][p];
    }
    // Outside the scope's view is masked in every frame but never occluded: it neither draws nor
    // scales the tissue's weights.
    for (std::size_t p = 0; p < clip.outside_view.size(); ++p) {
      if (clip.outside_view[p] != 0) tool_count[p] = 0;
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
  for (const auto& mask : clip.tool_mask) mask_frames_.push_back(mask.data());
  tables_ = {frames_.data(),
             int(frames_.size()),
             clip.width,
             clip.height,
             occlusion_weight_.empty() ? nullptr : occlusion_weight_.data(),
             mask_frames_.empty() ? nullptr : mask_frames_.data()};
}

float RaySampler::Weight(int frame, int pixel) const { return PixelWeight(tables_, frame, pixel); }

}  // namespace endorecon::train
