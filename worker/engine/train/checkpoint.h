// Files that hold a training run: a checkpoint (everything to resume exactly: config, trainer
// state with the optimiser, elapsed time and the curve so far) and the trained model (config,
// scene box and field only, for rendering). Both are written to a temporary file, flushed and
// renamed, so a crash never leaves a half-written file under the real name.
#pragma once

#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>

#include "common/prepare_flags.h"
#include "worker/engine/field/field.h"
#include "worker/engine/scene/scene_box.h"
#include "worker/engine/train/train_config.h"
#include "worker/engine/train/trainer.h"

namespace endorecon::train {

struct CheckpointExtras {
  double train_seconds = 0;
  nlohmann::json curve = nlohmann::json::array();
  // How the run's deformation started (FlowStartJson), kept through resumes; null in a checkpoint
  // written before it was recorded (DeformationStartOf then asks the trainer).
  nlohmann::json deformation_start;
  // The clip folder's frames the run trains on (--frames; every frame in a checkpoint that does not
  // say, written before 2026-12-06).
  FrameRange frames;
};

// How the run's deformation started, as its checkpoints and metrics.json record it: the account a
// resumed run carries from the run that began it, else the trainer's own (FlowStartJson).
nlohmann::json DeformationStartOf(const Trainer& trainer, const CheckpointExtras& extras);

void WriteCheckpoint(const std::filesystem::path& path, const Trainer& trainer,
                     const CheckpointExtras& extras);
// The config stored in a checkpoint, to build the Trainer that ReadCheckpointState then fills.
TrainConfig ReadCheckpointConfig(const std::filesystem::path& path);
// Throws Error(kDataLoss) for a corrupt or truncated file, kInvalidArgument for a file that is no checkpoint
// or one of other `frames` of its clip than the run's (before its state is read: a checkpoint of as many
// other frames resumed on them without a word).
CheckpointExtras ReadCheckpointState(const std::filesystem::path& path, Trainer& trainer,
                                     const FrameRange& frames = {});
// The iteration a run resumed from the checkpoint starts at, without building a trainer (how much
// progress a checkpoint holds: bench/fault_campaign). Throws as ReadCheckpointState.
int ReadCheckpointIteration(const std::filesystem::path& path);

struct Model {
  TrainConfig config;
  scene::SceneBox box;
  double near = 0, far = 1;
  std::unique_ptr<field::Field> field;
};

void WriteModel(const std::filesystem::path& path, const TrainConfig& config, const scene::SceneBox& box,
                double near, double far, const field::Field& field);
Model ReadModel(const std::filesystem::path& path);

}  // namespace endorecon::train
