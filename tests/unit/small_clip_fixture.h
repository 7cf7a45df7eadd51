// A small synthetic clip (8 frames, 48 x 40, tool and depth) shared by the tests of one suite,
// and the CPU preset sized for it: for tests that train.
#pragma once

#include <gtest/gtest.h>

#include <vector>

#include "tests/unit/temp_dir.h"
#include "worker/engine/scene/clip_loader.h"
#include "worker/engine/scene/synthetic_clip.h"
#include "worker/engine/train/scene_fit.h"
#include "worker/engine/train/train_config.h"

namespace endorecon::testing {

class SmallClipTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new TempDir("small-clip");
    scene::SynthOptions synth;
    synth.frames = 8;
    synth.width = 48;
    synth.height = 40;
    scene::WriteSyntheticClip(synth, dir_->path() / "clip");
    clip_ = new scene::Clip(scene::LoadClip(dir_->path() / "clip"));
  }
  static void TearDownTestSuite() {
    delete clip_;
    delete dir_;
    clip_ = nullptr;
    dir_ = nullptr;
  }

  // The CPU preset with 256 rays per batch and 400 iterations, fitted to the clip.
  static train::TrainConfig SmallConfig() {
    train::TrainConfig config = train::TrainConfig::Preset("cpu");
    config.rays_per_batch = 256;
    config.iterations = 400;
    train::FitToScene(*clip_, config);
    return config;
  }
  static std::vector<int> AllFrames() {
    std::vector<int> frames(clip_->frame_count());
    for (int i = 0; i < clip_->frame_count(); ++i) frames[i] = i;
    return frames;
  }

  static inline TempDir* dir_ = nullptr;
  static inline scene::Clip* clip_ = nullptr;
};

}  // namespace endorecon::testing
