// What a field is built from: the encoder, the grids, the blend, the deformation and the heads, with
// the two presets (the paper's sizes and a CPU-sized one; field_config.cc says why each value).
#pragma once

#include <array>
#include <cstddef>
#include <string>
#include <vector>

#include "worker/engine/field/deformation.h"
#include "worker/engine/field/frequency_encoder.h"
#include "worker/engine/field/grid_ensemble.h"
#include "worker/engine/field/heads.h"

namespace endorecon::field {

struct FieldConfig {
  // The canonical-space encoder: "hash" (the method: the grid ensemble blended in time) or
  // "frequency" (NeRF's positional encoding, EndoNeRF's encoder; the ablation's baseline: no grids,
  // no temporal blend, the density head takes the encoding directly).
  std::string encoding = "hash";
  int frequencies = 10;  // L of the frequency encoding
  GridEnsembleConfig grids;
  int blend_hidden = 16;  // width of the temporal blend's hidden layer
  DeformationConfig deformation;
  HeadsConfig heads;
  // Times of the exposure's knots (exposure.h): the training frames' when the run models exposure
  // (train_config.h "exposure"); empty: no exposure module, the colour head's output is the colour.
  std::vector<float> exposure_times;
  // A background learned per ray direction (background.h), when the run's background is "learned"
  // (train_config.h; FitToScene sets it). Off: what rays see past the samples is a fixed colour.
  bool learned_background = false;
  // The first and last times the field was trained at (FitToScene: the training frames'). Outside
  // them the deformation, the temporal blend and the colour head's time features hold their state at
  // the nearer end: a held-out last frame is rendered as the field stood at the last frame trained
  // on, not from a deformation knot only that frame's neighbours pulled on (docs/benchmarks.md).
  // The exposure takes the time itself (exposure.h predicts a held-out time's gain). Training
  // samples are at training times, inside the range, so the training step needs no clamp.
  std::array<float, 2> trained_times{0.0f, 1.0f};

  // The paper's sizes: grids {8, 16, 32} x scales {1.4, 1.7, 1.9}, 16 levels x 8 features, 2^19 tables.
  static FieldConfig Paper();
  // Sized for >= 1 M training samples/s on 2 cores.
  static FieldConfig Cpu();
};

// Throws InvalidArgument unless `times` is [first, last] with 0 <= first <= last <= 1 (finite).
// The field's parameter groups, in the order of its parameter blocks: each has its own learning rate
// (train_config.h, adam.lr).
inline constexpr std::array<const char*, 7> kParameterGroups = {"grid",  "blend",    "deform",    "density",
                                                                "color", "exposure", "background"};

// Hidden layers per head at most (the field keeps each layer's activations in a fixed array).
inline constexpr int kMaxHiddenLayers = 8;
// Units per hidden layer or feature width at most: wider layers size every sample's activations.
inline constexpr int kMostLayerWidth = 1024;
// The deformation grid's parameters at most (2^28 floats: 1 GiB, 4 GiB with its gradient and Adam's
// moments).
inline constexpr std::size_t kMostDeformationParams = std::size_t{1} << 28;

// The grid tables' parameters at most, counted as if every level used its whole table (2^28 floats:
// 1 GiB, 4 GiB with its gradient and Adam's moments; the paper's tables, 3 x 16 x 2^19 x 8, are
// 2^27.6). A tenant's --config of 2^26-slot tables at 64 levels wrote 5.6 GB of results from a 64 x 48
// clip (found 2026-12-06).
inline constexpr double kMostGridParams = double(std::size_t{1} << 28);

// The grid tables' parameters as if every level used its whole table: an upper bound.
double GridParamsBound(const GridEnsembleConfig& grids);
// Multiply-adds of the field's networks for one sample: the heads' layers, with the density head's
// input the levels' features (or the frequency encoding) and the colour head's the geometry features,
// 16 direction terms and its time features. An estimate for bounding a configuration's work.
double SampleMultiplyAdds(const FieldConfig& config);

void CheckTrainedTimes(const std::array<float, 2>& times);
// Refuses a configuration the field cannot be built from, naming the key (field.grids.log2_table, ...),
// before a clip is loaded: the modules' own constructors check again for their direct users.
void CheckFieldConfig(const FieldConfig& config);

}  // namespace endorecon::field
