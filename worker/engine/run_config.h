// What a run is configured with and which frames it trains on, settled before anything is built.
#pragma once

#include <nlohmann/json.hpp>
#include <vector>

#include "worker/engine/reconstruct.h"
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

// config.json: the resolved training configuration and the run's own settings (clip, seed, budget,
// threads), enough to reproduce the run.
nlohmann::json RunConfigJson(const train::TrainConfig& config, const ReconstructOptions& options,
                             int threads);

}  // namespace endorecon
