#include "tests/fuzz/tiny_run.h"

#include "worker/engine/scene/clip_loader.h"
#include "worker/engine/scene/synthetic_clip.h"

namespace endorecon::fuzz {

train::TrainConfig TinyConfig() {
  auto config = train::TrainConfig::Preset("cpu");
  config.rays_per_batch = 8;
  config.holdout = 0;
  config.occupancy_resolution = 4;
  config.field.grids.levels = 2;
  config.field.grids.log2_table = 4;
  config.field.deformation.resolution = 2;
  config.field.deformation.time_knots = 2;
  config.field.heads.density_hidden = {8};
  config.field.heads.color_hidden = {8};
  return config;
}

scene::Clip TinyClip(const std::filesystem::path& dir) {
  scene::SynthOptions options;
  options.frames = 2;
  options.width = 16;
  options.height = 12;
  scene::WriteSyntheticClip(options, dir);
  return scene::LoadClip(dir);
}

}  // namespace endorecon::fuzz
