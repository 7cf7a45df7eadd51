#include "worker/engine/field/field_config.h"

#include <fmt/format.h>

#include <cmath>
#include <string>

#include "common/error.h"
#include "worker/engine/field/exposure_times.h"

namespace endorecon::field {

void CheckTrainedTimes(const std::array<float, 2>& times) {
  const auto [first, last] = times;
  if (!(0 <= first && first <= last && last <= 1)) {  // NaN and infinities fail too
    FailInvalid("field.trained_times must be [first, last] with 0 <= first <= last <= 1");
  }
}

namespace {

double LayersMultiplyAdds(int inputs, const std::vector<int>& hidden, int outputs) {
  double sum = 0;
  double width = inputs;
  for (const int units : hidden) {
    sum += width * units;
    width = units;
  }
  return sum + width * outputs;
}

}  // namespace

double GridParamsBound(const GridEnsembleConfig& grids) {
  return double(grids.base_resolutions.size()) * grids.levels * std::ldexp(1.0, grids.log2_table) *
         grids.features;
}

double SampleMultiplyAdds(const FieldConfig& config) {
  const double density_inputs = config.encoding == "hash"
                                    ? double(config.grids.levels) * config.grids.features
                                    : 6.0 * config.frequencies + 3;
  const int geo = config.heads.geo_features;
  return LayersMultiplyAdds(int(density_inputs), config.heads.density_hidden, 2 + geo) +
         LayersMultiplyAdds(geo + 16 + 2 * config.heads.color_time_frequencies, config.heads.color_hidden, 4);
}

namespace {

void CheckLayers(const std::vector<int>& hidden, const std::string& key) {
  if (hidden.size() > std::size_t{kMaxHiddenLayers}) {
    FailInvalid(key + " may have at most " + std::to_string(kMaxHiddenLayers) + " hidden layers, got " +
                std::to_string(hidden.size()));
  }
  for (std::size_t i = 0; i < hidden.size(); ++i) {
    if (hidden[i] < 1 || hidden[i] > kMostLayerWidth) {
      FailInvalid(key + "[" + std::to_string(i) + "] must be in [1, " + std::to_string(kMostLayerWidth) +
                  "] units, got " + std::to_string(hidden[i]));
    }
  }
}

void CheckGrids(const GridEnsembleConfig& grids) {
  if (grids.base_resolutions.empty() || grids.base_resolutions.size() != grids.scales.size()) {
    FailInvalid("field.grids.base_resolutions and field.grids.scales need one entry per grid (at least one), "
                "got " + std::to_string(grids.base_resolutions.size()) + " and " +
                std::to_string(grids.scales.size()));
  }
  for (std::size_t i = 0; i < grids.scales.size(); ++i) {
    if (grids.base_resolutions[i] < 1) {
      FailInvalid("field.grids.base_resolutions[" + std::to_string(i) + "] must be >= 1, got " +
                  std::to_string(grids.base_resolutions[i]));
    }
    if (!(grids.scales[i] >= 1) || !std::isfinite(grids.scales[i])) {
      FailInvalid("field.grids.scales[" + std::to_string(i) + "] must be finite and >= 1, got " +
                  std::to_string(grids.scales[i]));
    }
  }
  const int f = grids.features;
  if (f != 1 && f != 2 && f != 4 && f != 8) {
    FailInvalid("field.grids.features must be 1, 2, 4 or 8, got " + std::to_string(f));
  }
  if (grids.log2_table < kLeastLog2Table || grids.log2_table > kMostLog2Table) {
    FailInvalid("field.grids.log2_table must be in [" + std::to_string(kLeastLog2Table) + ", " +
                std::to_string(kMostLog2Table) + "], got " + std::to_string(grids.log2_table));
  }
  if (grids.levels < 1) FailInvalid("field.grids.levels must be >= 1, got " + std::to_string(grids.levels));
  if (GridParamsBound(grids) > kMostGridParams) {
    FailInvalid(
        fmt::format("field.grids: {} grid(s) x {} levels x 2^{} slots x {} features are {:.3g} "
                    "parameters, more than {:.3g} (2^28: the paper's tables are 2.0e+08)",
                    grids.base_resolutions.size(), grids.levels, grids.log2_table, grids.features,
                    GridParamsBound(grids), kMostGridParams));
  }
  if (grids.max_resolution < 0) {
    FailInvalid("field.grids.max_resolution must be >= 0 (0: no cap), got " +
                std::to_string(grids.max_resolution));
  }
}

void CheckDeformation(const DeformationConfig& deformation) {
  if (!deformation.enabled) return;
  if (deformation.resolution < 1 || deformation.time_knots < 1) {
    FailInvalid("field.deformation.resolution and field.deformation.time_knots must be >= 1, got " +
                std::to_string(deformation.resolution) + " and " + std::to_string(deformation.time_knots));
  }
  // In doubles: (resolution + 1)^3 overflows an integer for resolutions the keys allow.
  const double side = double(deformation.resolution) + 1;
  const double params = side * side * side * 3 * double(deformation.time_knots);
  if (params > double(kMostDeformationParams)) {
    FailInvalid("field.deformation: a " + std::to_string(deformation.resolution) + "^3 grid with " +
                std::to_string(deformation.time_knots) + " time knots holds " + std::to_string(params) +
                " parameters, more than " + std::to_string(kMostDeformationParams));
  }
}

void CheckHeads(const HeadsConfig& heads) {
  CheckLayers(heads.density_hidden, "field.heads.density_hidden");
  CheckLayers(heads.color_hidden, "field.heads.color_hidden");
  if (heads.geo_features < 0 || heads.geo_features > kMostLayerWidth) {
    FailInvalid("field.heads.geo_features must be in [0, " + std::to_string(kMostLayerWidth) + "], got " +
                std::to_string(heads.geo_features));
  }
  if (!(heads.dropout >= 0 && heads.dropout < 1)) {
    FailInvalid("field.heads.dropout must be in [0, 1), got " + std::to_string(heads.dropout));
  }
  if (!(heads.color_dropout < 1)) {
    FailInvalid("field.heads.color_dropout must be below 1 (negative: field.heads.dropout), got " +
                std::to_string(heads.color_dropout));
  }
  if (heads.color_time_frequencies < 0 || heads.color_time_frequencies > kMaxTimeFrequencies) {
    FailInvalid("field.heads.color_time_frequencies must be in [0, " + std::to_string(kMaxTimeFrequencies) +
                "], got " + std::to_string(heads.color_time_frequencies));
  }
}

}  // namespace

void CheckFieldConfig(const FieldConfig& config) {
  if (config.encoding == "frequency") {
    if (config.frequencies < 1 || config.frequencies > kMostFrequencies) {
      FailInvalid("field.frequencies must be in [1, " + std::to_string(kMostFrequencies) + "], got " +
                  std::to_string(config.frequencies));
    }
  } else if (config.encoding == "hash") {
    CheckGrids(config.grids);
    if (config.blend_hidden < 1 || config.blend_hidden > kMostLayerWidth) {
      FailInvalid("field.blend_hidden must be in [1, " + std::to_string(kMostLayerWidth) + "], got " +
                  std::to_string(config.blend_hidden));
    }
  } else {
    FailInvalid("field.encoding must be hash or frequency, got '" + config.encoding + "'");
  }
  CheckDeformation(config.deformation);
  CheckHeads(config.heads);
  CheckTrainedTimes(config.trained_times);
  CheckExposureTimes(config.exposure_times);
}

FieldConfig FieldConfig::Paper() {
  FieldConfig c;
  c.grids.base_resolutions = {8, 16, 32};
  c.grids.scales = {1.4, 1.7, 1.9};
  c.grids.levels = 16;
  c.grids.features = 8;
  c.grids.log2_table = 19;
  c.deformation.resolution = 32;
  c.deformation.time_knots = 16;
  c.heads.density_hidden = {64};
  c.heads.color_hidden = {64, 64};
  return c;
}

// Sized on this machine kind (2 cores, AVX-512; bench/field_bench, 32768-sample batches): 3 grids x 10
// levels x 2 features reach resolutions ~550-660 (a pixel's footprint for clips up to ~640 wide), 2^14-slot
// tables (128 KiB per level, 3.5 MiB in all) stay in L2/L3 between steps (2^15 cost ~15% more), heads of
// 32 hidden units (2304 multiply-adds per sample; 256 more with the colour head's time inputs) keep the MLPs
// near a third of the time. Forward + backward: ~2.4 M samples/s on 2 threads (~3.2 M without deformation);
// forward alone ~8.4 M.
FieldConfig FieldConfig::Cpu() {
  FieldConfig c;
  c.grids.base_resolutions = {8, 16, 32};
  c.grids.scales = {1.6, 1.5, 1.4};
  c.grids.levels = 10;
  c.grids.features = 2;
  c.grids.log2_table = 14;
  // A 12^3 deformation grid rather than 16^3: held out on the real-texture clip at 120 s 27.53 and
  // 27.68 dB against 27.39 and 27.40 (the demo clip 32.98 against 32.94 dB; docs/benchmarks.md,
  // "A coarser deformation grid"); 24^3 had lost 0.6 dB.
  // 12 time knots rather than 8 (one every 4 frames of a 48-frame clip): on the real-texture clip at
  // 120 s +0.12 dB held out (three pairs of runs) and +0.3 dB on the training frames against the
  // truth; the demo clip the same at 120 s, +0.03-0.08 dB at 300 s at the same depth
  // (docs/benchmarks.md, "Twelve time knots"). More knots cost nothing measurable: a sample reads two
  // time slices whatever their number.
  c.deformation.resolution = 12;
  c.deformation.time_knots = 12;
  c.heads.density_hidden = {32};
  c.heads.color_hidden = {32};
  // The colour sees the time (4 frequencies, 8 inputs): at 120 s, +0.4 dB held out on the demo clip
  // and on the real-texture clip, whose speculars follow a moving light (docs/benchmarks.md,
  // "Time in the colour head").
  c.heads.color_time_frequencies = 4;
  return c;
}

}  // namespace endorecon::field
