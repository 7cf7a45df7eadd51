// One training run's state and its step: pick rays, sample along them, evaluate the field,
// composite, compute the loss, backpropagate by hand, step Adam.
#pragma once

#include <cstdint>
#include <iosfwd>
#include <memory>
#include <vector>

#include "worker/engine/field/field.h"
#include "worker/engine/render/occupancy_grid.h"
#include "worker/engine/scene/clip.h"
#include "worker/engine/scene/scene_box.h"
#include "worker/engine/train/adam.h"
#include "worker/engine/train/depth_refiner.h"
#include "worker/engine/train/ray_sampler.h"
#include "worker/engine/train/train_config.h"
#include "worker/engine/train/uncertainty_map.h"

namespace endorecon::train {

struct StepStats {
  double loss = 0;
  double rgb_mse = 0;  // of the rendered colour on the batch's (tissue) pixels, colours in [0, 1]
  double psnr = 0;
  long long samples = 0;
  int guided_rays = 0;         // rays drawn from the uncertainty map (0 before the adaptive warm-up ends)
  bool depth_refined = false;  // a depth-refinement round ran before this step
};

// The occupancy grid of a field as the configuration asks (empty when occupancy_resolution is 0),
// probed at one time for a static field (no deformation), at several for a dynamic one.
render::OccupancyGrid BuildOccupancy(field::Field& field, const TrainConfig& config);

class Trainer {
 public:
  // Keeps references to clip (which must outlive the trainer). train_frames: the frames rays come from.
  Trainer(const scene::Clip& clip, const TrainConfig& config, std::vector<int> train_frames,
          std::uint64_t seed);
  ~Trainer();

  // One iteration at `progress` in [0, 1] of the run (drives the learning-rate decay and the periodic
  // rounds; a RunClock's Progress; negative: by iterations alone, RunProgress(iteration, iterations)). Throws
  // Error(kInternal) naming the stage and iteration when the loss or a gradient is not finite; the parameters
  // are then still those of the last good step.
  StepStats Step(double progress = -1);

  int iteration() const { return iteration_; }
  field::Field& field() { return *field_; }
  const scene::SceneBox& box() const { return box_; }
  const TrainConfig& config() const { return config_; }

  const UncertaintyMap& uncertainty_map() const { return map_; }
  const DepthRefiner& depth_refiner() const { return refiner_; }
  // The occupancy grid the samplers use (empty until the first rebuild, or when switched off).
  const render::OccupancyGrid& occupancy() const { return occupancy_; }
  // Rebuilds it from the field now (Step does so on the configured schedule).
  void RebuildOccupancy();
  // The mean share of [near, far] the grid leaves to be sampled, over a lattice of pixels of the
  // first training frame (1 with no grid).
  double occupancy_span_fraction() const;
  // One depth-refinement round now (Step runs them on the configured schedule).
  DepthRefineStats RefineDepth();

  // Exact state for resume: field, optimiser, iteration, the uncertainty map, the refined depth
  // priors and the occupancy grid (the rays of a step depend only on the seed, the iteration and the map, and
  // their samples on the priors, so a resumed run repeats the same loss curve).
  void Save(std::ostream& out) const;
  void Load(std::istream& in);

 private:
  struct Batch;
  void SampleRays(int guided);
  // Fills ray r of the batch for (frame, pixel) with the ordinary (depth-guided) samples.
  void PlaceRay(int r, const RayPick& pick, std::uint64_t step_seed);
  // Re-places the stratified samples of rays [0, rays) (all of a ray's samples when it has no depth
  // prior) in proportion to the sample scores from one dropout-on pass at stratified probes of the
  // ray (adaptive_sampler.h), with the floor adaptive_floor; the Gaussian samples around the prior stay.
  void ReallocateSamples(int rays, std::uint64_t step_seed);
  // One dropout-on pass at every cell's probe pixel; the ray scores of the aleatoric variances.
  void RefreshMap();
  double LossAndGradients(StepStats& stats);

  const scene::Clip& clip_;
  TrainConfig config_;
  std::uint64_t seed_;
  scene::SceneBox box_;
  RaySampler sampler_;
  std::unique_ptr<field::Field> field_;
  std::unique_ptr<Adam> adam_;
  std::unique_ptr<Batch> batch_;
  UncertaintyMap map_;
  DepthRefiner refiner_;
  render::OccupancyGrid occupancy_;
  int occupancy_builds_ = 0;
  int iteration_ = 0;
};

}  // namespace endorecon::train
