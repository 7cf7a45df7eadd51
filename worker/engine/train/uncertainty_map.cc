#include "worker/engine/train/uncertainty_map.h"

#include <algorithm>
#include <cmath>
#include <istream>
#include <ostream>
#include <string>

#include "common/error.h"
#include "worker/engine/base/counter_rng.h"

namespace endorecon::train {

UncertaintyMap::UncertaintyMap(const RaySampler& sampler, int width, int height, int stride)
    : sampler_(sampler),
      stride_(stride),
      cells_x_((width + stride - 1) / stride),
      cells_y_((height + stride - 1) / stride) {
  for (int f : sampler.frames()) {
    for (int cy = 0; cy < cells_y_; ++cy) {
      for (int cx = 0; cx < cells_x_; ++cx) {
        // The probe is the tissue pixel nearest the cell's centre.
        const int x0 = cx * stride, y0 = cy * stride;
        const int x1 = std::min(width, x0 + stride), y1 = std::min(height, y0 + stride);
        const double mx = 0.5 * (x0 + x1 - 1), my = 0.5 * (y0 + y1 - 1);
        RayPick probe{f, -1};
        double best = 0;
        for (int y = y0; y < y1; ++y) {
          for (int x = x0; x < x1; ++x) {
            const double d = (x - mx) * (x - mx) + (y - my) * (y - my);
            if (sampler.Weight(f, y * width + x) > 0 && (probe.pixel < 0 || d < best)) {
              probe.pixel = y * width + x;
              best = d;
            }
          }
        }
        probe_.push_back(probe);
      }
    }
  }
  scores_.assign(probe_.size(), 0.0f);
  cumulative_.assign(probe_.size(), 0.0);
}

void UncertaintyMap::Set(std::vector<float> scores, int iteration) {
  if (scores.size() != probe_.size()) {
    FailInvalid("uncertainty map: " + std::to_string(scores.size()) + " scores for " +
                std::to_string(probe_.size()) + " cells");
  }
  scores_ = std::move(scores);
  iteration_ = iteration;
  double sum = 0;
  for (std::size_t i = 0; i < scores_.size(); ++i) {
    const float v = scores_[i];
    if (probe_[i].pixel >= 0 && v > 0 && std::isfinite(v)) sum += v;
    cumulative_[i] = sum;
  }
  total_ = sum;
}

MapTables UncertaintyMap::tables() const {
  return {probe_.data(), cumulative_.data(), cells(), total_, stride_, cells_x_, cells_y_};
}

std::optional<RayPick> UncertaintyMap::Pick(std::uint64_t seed, std::uint64_t stream) const {
  RayPick pick;
  if (!PickFromMap(tables(), sampler_.tables(), seed, stream, &pick)) return std::nullopt;
  return pick;
}

void UncertaintyMap::Save(std::ostream& out) const {
  const std::int64_t count = std::int64_t(scores_.size());
  out.write(reinterpret_cast<const char*>(&iteration_), sizeof(iteration_));
  out.write(reinterpret_cast<const char*>(&count), sizeof(count));
  out.write(reinterpret_cast<const char*>(scores_.data()), std::streamsize(scores_.size() * sizeof(float)));
}

void UncertaintyMap::Load(std::istream& in) {
  int iteration = -1;
  std::int64_t count = 0;
  in.read(reinterpret_cast<char*>(&iteration), sizeof(iteration));
  in.read(reinterpret_cast<char*>(&count), sizeof(count));
  if (!in) Fail(ErrorCode::kDataLoss, "checkpoint: truncated before the uncertainty map");
  if (count != std::int64_t(probe_.size())) {
    Fail(ErrorCode::kDataLoss,
         "checkpoint: uncertainty map has " + std::to_string(count) + " cells, expected " +
             std::to_string(probe_.size()) +
             " (a checkpoint of another clip, or of another --holdout or --frames, is resumed "
             "only on its own)");
  }
  std::vector<float> scores(probe_.size());
  in.read(reinterpret_cast<char*>(scores.data()), std::streamsize(scores.size() * sizeof(float)));
  if (!in) Fail(ErrorCode::kDataLoss, "checkpoint: truncated inside the uncertainty map");
  Set(std::move(scores), iteration);
}

}  // namespace endorecon::train
