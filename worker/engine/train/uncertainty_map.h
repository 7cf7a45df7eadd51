// A coarse per-pixel uncertainty map of the training frames that uncertainty-guided ray selection
// draws from (paper §3, adaptive sampling): the frames are cut into stride x stride cells, each cell
// holds one score (the ray score rendered at its probe pixel), and a pick chooses a cell in proportion
// to its score, then a tissue pixel of that cell uniformly. Tool pixels are never picked: a cell
// without tissue has no probe and weight 0, and picks inside a cell reject tool pixels.
#pragma once

#include <cstdint>
#include <iosfwd>
#include <optional>
#include <vector>

#include "worker/engine/train/ray_sampler.h"

namespace endorecon::train {

class UncertaintyMap {
 public:
  // Cells of `sampler.frames()` (the training frames with tissue); sampler must outlive the map.
  UncertaintyMap(const RaySampler& sampler, int width, int height, int stride);

  int cells() const { return int(probe_.size()); }
  // The frame and the pixel whose ray score stands for cell i; pixel -1 for a cell without tissue.
  RayPick probe(int cell) const { return probe_[cell]; }

  // Replaces the scores (one per cell; negative or non-finite count as 0) and notes the iteration.
  // Throws InvalidArgument when the count differs from cells().
  void Set(std::vector<float> scores, int iteration);
  bool ready() const { return total_ > 0; }     // some cell has a positive score
  int iteration() const { return iteration_; }  // of the last Set, -1 before any
  const std::vector<float>& scores() const { return scores_; }

  // A pick in proportion to the cell scores, a pure function of (seed, stream); nullopt when no cell
  // has a positive score.
  std::optional<RayPick> Pick(std::uint64_t seed, std::uint64_t stream) const;
  // The tables PickFromMap reads (they point into this map).
  MapTables tables() const;

  void Save(std::ostream& out) const;
  void Load(std::istream& in);  // Error(kDataLoss) for a truncated stream or another cell count

 private:
  const RaySampler& sampler_;
  int stride_, cells_x_, cells_y_;
  std::vector<RayPick> probe_;
  std::vector<float> scores_;
  std::vector<double> cumulative_;  // inclusive prefix sums of scores_
  double total_ = 0;
  int iteration_ = -1;
};

}  // namespace endorecon::train
