// The smallest training run: what the checkpoint and model harnesses load into, and what the seed
// maker writes their seeds from (a seed must fit the harness's field block for block).
#pragma once

#include <filesystem>

#include "worker/engine/scene/clip.h"
#include "worker/engine/train/train_config.h"

namespace endorecon::fuzz {

// The CPU preset shrunk to a few thousand parameters (2 levels, 16-slot tables, 8-unit heads).
train::TrainConfig TinyConfig();

// A 2-frame 16x12 synthetic clip, written under `dir` and loaded.
scene::Clip TinyClip(const std::filesystem::path& dir);

}  // namespace endorecon::fuzz
