// One training run's state and its schedule: the field, the uncertainty map, the refined depth priors,
// the occupancy grid and the seeds; each step's loops (pick rays, sample along them, evaluate the
// field, composite, compute the loss, backpropagate by hand, step Adam) run on a StepBackend
// (step_backend.h): the CPU's by default, a GPU's when the caller gives its factory.
#pragma once

#include <cstdint>
#include <iosfwd>
#include <memory>
#include <string>
#include <vector>

#include "worker/engine/field/field.h"
#include "worker/engine/render/occupancy_grid.h"
#include "worker/engine/render/render_backend.h"
#include "worker/engine/scene/clip.h"
#include "worker/engine/scene/scene_box.h"
#include "worker/engine/train/depth_refiner.h"
#include "worker/engine/train/flow_start.h"
#include "worker/engine/train/ray_sampler.h"
#include "worker/engine/train/step_backend.h"
#include "worker/engine/train/train_config.h"
#include "worker/engine/train/training_ray.h"
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
render::OccupancyGrid BuildOccupancy(const render::DensityProbe& density, const TrainConfig& config);
render::OccupancyGrid BuildOccupancy(field::Field& field, const TrainConfig& config);

class Trainer {
 public:
  // Keeps references to clip (which must outlive the trainer). train_frames: the frames rays come from.
  // `backend` makes the step backend (MakeCpuStep by default), `render` the depth refinement's renderer's.
  Trainer(const scene::Clip& clip, const TrainConfig& config, std::vector<int> train_frames,
          std::uint64_t seed, const StepBackendFactory& backend = MakeCpuStep,
          render::RenderBackendFactory render = render::MakeCpuRender);
  ~Trainer();

  // One iteration at `progress` in [0, 1] of the run (drives the learning-rate decay and the periodic
  // rounds; a RunClock's Progress; negative: by iterations alone, RunProgress(iteration, iterations)). Throws
  // Error(kInternal) naming the stage and iteration when the loss or a gradient is not finite; the parameters
  // are then still those of the last good step.
  StepStats Step(double progress = -1);

  int iteration() const { return iteration_; }
  // The host field. With a GPU backend its parameters are the last SyncField's: call it before reading.
  field::Field& field() { return *field_; }
  void SyncField() { backend_->PullField(); }
  // Where the steps run ("cpu", "cuda:0 (...)").
  std::string device() const { return backend_->device(); }
  const scene::SceneBox& box() const { return box_; }
  const TrainConfig& config() const { return config_; }
  // How the deformation started (train/flow_start.h): `skipped` says why not from the flow (config
  // "zero", a static scene, no frame at time 0, ...). The fit runs in StartDeformation (or the first Step),
  // so a trainer loaded from a checkpoint never runs it (`skipped` then says so; the checkpoint carries the
  // first run's account).
  const FlowStart& deformation_start() const { return deformation_start_; }
  // Fits that start now, if it is still to be fitted (the first Step does otherwise; a run calls it
  // before its clock starts, so the steps' timing holds no start-up work), and hands it to the backend.
  void StartDeformation();

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
  // The iteration at the start of what Save wrote, read without loading the rest (the checkpoint's
  // progress). Throws Error(kDataLoss) when `in` ends first.
  static int ReadIteration(std::istream& in);

 private:
  // Points the step tables at the current priors, occupancy grid and map (after a refinement, a
  // rebuild, a refresh, Load) and tells the backend.
  void UpdateTables();
  // One dropout-on pass at every cell's probe pixel; the ray scores of the aleatoric variances.
  void RefreshMap();

  const scene::Clip& clip_;
  TrainConfig config_;
  std::uint64_t seed_;
  scene::SceneBox box_;
  RaySampler sampler_;
  std::unique_ptr<field::Field> field_;
  FlowStart deformation_start_;
  bool start_pending_ = false;  // deformation_start "flow", not yet fitted (nor loaded)
  UncertaintyMap map_;
  DepthRefiner refiner_;
  render::OccupancyGrid occupancy_;
  int occupancy_builds_ = 0;
  std::vector<const std::uint8_t*> rgb_frames_;
  std::vector<const float*> prior_frames_;
  std::vector<scene::PinholeView> views_;
  StepTables tables_;
  std::unique_ptr<StepBackend> backend_;
  render::RenderBackendFactory render_;  // the depth refinement renderer's backend
  int iteration_ = 0;
};

}  // namespace endorecon::train
