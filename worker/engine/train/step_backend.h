// Where a training step runs. There is one Trainer (the schedule, the seeds, the uncertainty map, the
// refined priors, the occupancy grid, checkpoints); it drives a StepBackend, which decides only where
// the batch and the parameters live and how the step's loops are launched. Both backends run the
// per-ray bodies of step_math.h and the field's modules' math; the CPU backend (MakeCpuStep, the
// reference) on the host field, a GPU backend (cuda/, built with CUDA) on a device copy of it.
#pragma once

#include <cstdint>
#include <functional>
#include <iosfwd>
#include <memory>
#include <string>
#include <vector>

#include "worker/engine/field/field.h"
#include "worker/engine/train/ray_picks.h"
#include "worker/engine/train/step_math.h"
#include "worker/engine/train/train_config.h"

namespace endorecon::train {

struct StepRequest {
  int iteration = 0;
  std::uint64_t step_seed = 0;     // picks and samples
  std::uint64_t dropout_seed = 0;  // the forward pass's masks
  int guided = 0;                  // rays 0..guided-1 drawn from the uncertainty map
  double progress = 0;             // of the run, for the learning-rate decay
};

struct StepResult {
  double loss = 0;
  double rgb_mse = 0;  // mean over the batch's rays, colours in [0, 1]
  long long samples = 0;
};

class StepBackend {
 public:
  virtual ~StepBackend() = default;

  // "cpu", or the GPU's name ("cuda:0 (NVIDIA H200)"), for logs and metrics.json.
  virtual std::string device() const = 0;
  // The tables (priors, occupancy, map) changed: a backend that keeps copies refreshes them.
  virtual void TablesChanged() = 0;
  // Rays, samples (guided rays re-placed), forward with dropout, loss, backward, Adam. Throws
  // Error(kInternal) naming the stage and the iteration when the loss or a gradient is not finite;
  // the parameters are then those of the last good step.
  virtual StepResult Step(const StepRequest& request) = 0;
  // The uncertainty map's probe rays placed from `probes` with `seed`, one dropout-on pass each:
  // their ray scores, in order.
  virtual std::vector<float> ProbeScores(const std::vector<RayPick>& probes, std::uint64_t seed) = 0;
  // The field's density at a batch of points in host memory (the occupancy grid's probes), from the
  // parameters where they live: no PullField needed.
  virtual void Densities(const field::SampleBatch& batch, float* sigma) = 0;
  // Device parameters into the host field (before anything reads it: periodic rounds, checkpoints,
  // rendering), and back after the host field was loaded. No-ops on the CPU.
  virtual void PullField() = 0;
  virtual void PushField() = 0;
  // The optimiser's state, in train::Adam's stream format on every backend.
  virtual void SaveOptimizer(std::ostream& out) const = 0;
  virtual void LoadOptimizer(std::istream& in) = 0;
};

// Makes a backend for the trainer's host field, configuration and tables (which outlive it).
using StepBackendFactory = std::function<std::unique_ptr<StepBackend>(
    field::Field& field, const TrainConfig& config, const StepTables& tables)>;

std::unique_ptr<StepBackend> MakeCpuStep(field::Field& field, const TrainConfig& config,
                                         const StepTables& tables);

}  // namespace endorecon::train
