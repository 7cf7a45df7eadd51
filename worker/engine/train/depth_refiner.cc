#include "worker/engine/train/depth_refiner.h"

#include <algorithm>
#include <cmath>
#include <istream>
#include <ostream>

#include "common/error.h"
#include "worker/engine/train/depth_fill.h"
#include "worker/engine/train/losses.h"

namespace endorecon::train {

DepthRefiner::DepthRefiner(const scene::Clip& clip, std::vector<int> frames, double fill_sigma)
    : clip_(clip),
      frames_(std::move(frames)),
      refined_(std::size_t(clip.frame_count())),
      filled_frames_(std::size_t(clip.frame_count())) {
  if (!(fill_sigma > 0) || !clip.has_depth()) return;
  for (int f : frames_) {
    FilledDepth filled =
        FillDepthHoles(clip.depth[std::size_t(f)],
                       clip.has_masks() ? std::span<const std::uint8_t>(clip.tool_mask[std::size_t(f)])
                                        : std::span<const std::uint8_t>(),
                       clip.width, clip.height, fill_sigma);
    filled_ += filled.filled;
    left_ += filled.left;
    if (filled.filled > 0) filled_frames_[std::size_t(f)] = std::move(filled.depth);
  }
}

DepthRefineStats DepthRefiner::Refine(render::FrameRenderer& renderer, float fraction, float ema,
                                      std::size_t max_pixels) {
  DepthRefineStats stats;
  if (!clip_.has_depth() || frames_.empty()) return stats;
  const std::size_t pixels = std::size_t(clip_.width) * std::size_t(clip_.height);
  std::vector<int> measured;
  std::vector<float> rendered, disagreement;
  double shift = 0;
  for (std::size_t visited = 0; visited < frames_.size(); ++visited) {
    if (max_pixels > 0 && visited > 0 && stats.measured >= max_pixels) break;
    const int f = frames_[next_];
    next_ = (next_ + 1) % frames_.size();
    auto& prior = refined_[std::size_t(f)];
    if (prior.empty()) prior = Unrefined(f);
    measured.clear();
    for (std::size_t p = 0; p < pixels; ++p) {
      const bool tool = clip_.has_masks() && clip_.tool_mask[std::size_t(f)][p] != 0;
      if (!tool && HasDepthPrior(prior[p])) measured.push_back(int(p));
    }
    if (measured.empty()) continue;
    rendered.resize(measured.size());
    std::vector<float> opacity(measured.size()), rgb(3 * measured.size());
    render::PixelOutputs out{rgb.data(), rendered.data(), opacity.data()};
    renderer.RenderPixels(clip_.cameras[std::size_t(f)], clip_.times[std::size_t(f)], measured.data(),
                          int(measured.size()), out);
    disagreement.resize(measured.size());
    for (std::size_t i = 0; i < measured.size(); ++i) {
      disagreement[i] = std::fabs(rendered[i] - prior[std::size_t(measured[i])]);
    }
    // The worst `fraction` of this frame's measured pixels: those at or above the quantile.
    const std::size_t keep = std::size_t(std::floor(double(1.0f - fraction) * double(measured.size())));
    std::vector<float> sorted = disagreement;
    std::nth_element(sorted.begin(), sorted.begin() + std::ptrdiff_t(std::min(keep, sorted.size() - 1)),
                     sorted.end());
    const float threshold = sorted[std::min(keep, sorted.size() - 1)];
    stats.measured += measured.size();
    for (std::size_t i = 0; i < measured.size(); ++i) {
      if (disagreement[i] < threshold || !std::isfinite(rendered[i]) || disagreement[i] == 0.0f) continue;
      float& value = prior[std::size_t(measured[i])];
      const float next = value + ema * (rendered[i] - value);
      shift += std::fabs(next - value);
      value = next;
      ++stats.moved;
    }
  }
  stats.mean_shift = stats.moved > 0 ? shift / double(stats.moved) : 0.0;
  ++rounds_;
  return stats;
}

void DepthRefiner::Save(std::ostream& out) const {
  const std::int32_t rounds = rounds_;
  const std::int64_t frames = std::int64_t(refined_.size()), next = std::int64_t(next_);
  out.write(reinterpret_cast<const char*>(&rounds), sizeof(rounds));
  out.write(reinterpret_cast<const char*>(&next), sizeof(next));
  out.write(reinterpret_cast<const char*>(&frames), sizeof(frames));
  for (const auto& frame : refined_) {
    const std::int64_t size = std::int64_t(frame.size());
    out.write(reinterpret_cast<const char*>(&size), sizeof(size));
    out.write(reinterpret_cast<const char*>(frame.data()), std::streamsize(frame.size() * sizeof(float)));
  }
}

void DepthRefiner::Load(std::istream& in) {
  std::int32_t rounds = 0;
  std::int64_t frames = 0, next = 0;
  in.read(reinterpret_cast<char*>(&rounds), sizeof(rounds));
  in.read(reinterpret_cast<char*>(&next), sizeof(next));
  in.read(reinterpret_cast<char*>(&frames), sizeof(frames));
  if (!in) Fail(ErrorCode::kDataLoss, "checkpoint: truncated before the refined depth priors");
  if (next < 0 || (next > 0 && std::size_t(next) >= frames_.size())) {
    Fail(ErrorCode::kDataLoss, "checkpoint: depth refinement resumes at frame " + std::to_string(next) +
                                   " of " + std::to_string(frames_.size()));
  }
  if (frames != std::int64_t(refined_.size())) {
    Fail(ErrorCode::kDataLoss, "checkpoint: refined depth priors for " + std::to_string(frames) +
                                   " frames, the clip has " + std::to_string(refined_.size()));
  }
  const std::int64_t pixels = std::int64_t(clip_.width) * clip_.height;
  for (auto& frame : refined_) {
    std::int64_t size = 0;
    in.read(reinterpret_cast<char*>(&size), sizeof(size));
    if (!in || (size != 0 && size != pixels)) {
      Fail(ErrorCode::kDataLoss, "checkpoint: a refined depth prior of " + std::to_string(size) +
                                     " pixels, expected 0 or " + std::to_string(pixels));
    }
    frame.resize(std::size_t(size));
    in.read(reinterpret_cast<char*>(frame.data()), std::streamsize(frame.size() * sizeof(float)));
    if (!in) Fail(ErrorCode::kDataLoss, "checkpoint: truncated inside the refined depth priors");
  }
  rounds_ = rounds;
  next_ = std::size_t(next);
}

}  // namespace endorecon::train
