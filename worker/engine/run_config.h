// What a run is configured with and which frames it trains on, settled before anything is built.
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "worker/engine/reconstruct.h"
#include "worker/engine/render/render_backend.h"
#include "worker/engine/train/step_backend.h"
#include "worker/engine/train/train_config.h"

namespace endorecon {

// The preset (or, on resume, the checkpoint's configuration) with options.config, iterations and
// holdout over it. Throws Error(kInvalidArgument) for an unknown preset or key, a bad value, or a
// config that is not a JSON object.
train::TrainConfig ResolveConfig(const ReconstructOptions& options);

struct FrameSplit {
  std::vector<int> train, heldout;
};

// Every K-th frame (K-1, 2K-1, ...) is held out; frame 0, which fixes the canonical space, never is.
FrameSplit SplitFrames(int frames, int holdout);

// Where a run's training steps and renders go.
struct DeviceBackends {
  train::StepBackendFactory step;
  render::RenderBackendFactory render;
};

// The backends of a device: "cpu", or "cuda:N" (N a CUDA device index, as CUDA_VISIBLE_DEVICES leaves
// them). Throws Error(kInvalidArgument) naming the device and why when it cannot be used: another form,
// a build without CUDA, no such device (with the devices there are). Never falls back to the CPU.
DeviceBackends BackendsFor(const std::string& device);

// config.json: the resolved training configuration and the run's own settings (clip, seed, budget,
// threads), enough to reproduce the run.
nlohmann::json RunConfigJson(const train::TrainConfig& config, const ReconstructOptions& options,
                             int threads);

}  // namespace endorecon
