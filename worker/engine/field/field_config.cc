#include "worker/engine/field/field_config.h"

#include "common/error.h"

namespace endorecon::field {

void CheckTrainedTimes(const std::array<float, 2>& times) {
  const auto [first, last] = times;
  if (!(0 <= first && first <= last && last <= 1)) {  // NaN and infinities fail too
    FailInvalid("field.trained_times must be [first, last] with 0 <= first <= last <= 1");
  }
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
