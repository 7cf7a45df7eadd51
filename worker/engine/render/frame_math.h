// The per-ray bodies of rendering a chunk of pixels (render_backend.h), shared by the CPU backend
// (cpu_render.cc, tbb loops) and the GPU one (cuda/device_render.cu, kernels), so the two render the
// same rays with one copy of the math. A chunk is laid out ray-major: ray r's coarse samples at
// r * coarse, its fine samples at r * fine (arrays sized for the larger of the two).
// The order of a chunk: PlaceCoarseRay, the field's density at the coarse samples, CoarseWeights,
// PlaceFineRay, the field at the fine samples (once without dropout, or K dropout passes folded in
// by AddDropoutPass and FinishDropoutPasses), FinishRay into the renderer's PixelOutputs (device
// arrays on a GPU).
#pragma once

#include <cstddef>
#include <cstdint>

#include "common/hd.h"
#include "worker/engine/field/background_math.h"
#include "worker/engine/field/variance.h"
#include "worker/engine/render/adaptive_sampler.h"
#include "worker/engine/render/camera_ray.h"
#include "worker/engine/render/mc_dropout.h"
#include "worker/engine/render/render_backend.h"
#include "worker/engine/render/sample_score.h"
#include "worker/engine/render/stratified_sampler.h"
#include "worker/engine/render/volume_renderer.h"

namespace endorecon::render {

// Rendering is deterministic (the same model gives the same images): coarse samples at bin centres,
// fine ones at the middle of their quantile bins.
struct BinCentre {
  ENDORECON_HD float operator()(unsigned) const { return 0.5f; }
};

// What every ray of a chunk shares.
struct ChunkShape {
  scene::PinholeView view;
  scene::BoxFrame box;
  OccupancyView occupancy;  // no cells: the whole box span is sampled
  float near = 0, far = 1, time = 0;
  int coarse = 0, fine = 0;                  // samples per ray
  float floor = 0;                           // share of fine samples spread uniformly
  const float* background = nullptr;         // RGB past the samples (when no learned background)
  const float* background_params = nullptr;  // the field's learned background, or null
};

// A chunk's working arrays (see the layout above); every pointer in one memory space.
struct ChunkArrays {
  CameraRay* rays = nullptr;
  float *s = nullptr, *delta = nullptr, *pos = nullptr, *dir = nullptr, *time = nullptr;
  float *sigma = nullptr, *sigma_lv = nullptr, *color = nullptr, *color_lv = nullptr;
  float *weights = nullptr, *coarse_s = nullptr;

  ENDORECON_HD RaySlot Slot(int r, int samples) const {
    return RaySlotOf(s, delta, pos, dir, time, r, samples);
  }
};

// The K dropout passes of the fine samples (with uncertainty only): per sample its moments and, once
// finished, its total, aleatoric and epistemic variances of density and colour.
struct DropoutArrays {
  McMoments<float>* density = nullptr;  // one per sample
  McMoments<float>* color = nullptr;    // three per sample
  float* var_density[3] = {nullptr, nullptr, nullptr};
  float* var_color[3] = {nullptr, nullptr, nullptr};
};

// The shape of a chunk of `camera` at `time` as a renderer's settings ask; `background` (the
// settings' colour, in the backend's memory) and `background_params` (the field's learned
// background, or null) in the memory the per-ray bodies run in.
inline ChunkShape ChunkShapeOf(const FrameRenderSettings& settings, const scene::SceneBox& box,
                               const scene::Camera& camera, float time, const OccupancyView& occupancy,
                               const float* background, const float* background_params) {
  ChunkShape shape;
  shape.view = camera.View();
  shape.box = box.Frame();
  shape.occupancy = occupancy;
  shape.near = static_cast<float>(settings.near);
  shape.far = static_cast<float>(settings.far);
  shape.time = time;
  shape.coarse = settings.coarse_samples;
  shape.fine = settings.fine_samples;
  shape.floor = settings.floor;
  shape.background = background;
  shape.background_params = background_params;
  return shape;
}

// Ray r of the chunk (pixel `pixel` of the view): its span, and its coarse samples as field inputs.
ENDORECON_HD void PlaceCoarseRay(const ChunkShape& shape, const ChunkArrays& a, int pixel, int r) {
  a.rays[r] = CameraRayOfPixel(shape.view, pixel, shape.box, shape.occupancy, shape.near, shape.far);
  PlaceSamples(
      a.rays[r], shape.box, shape.time, shape.coarse,
      [&](float lo, float hi, float* s, float* delta) {
        StratifiedSamples(lo, hi, shape.coarse, BinCentre{}, s, delta);
      },
      a.Slot(r, shape.coarse));
}

// The coarse samples' weights from their density (their colour is not read into anything used), and
// their depths kept for the fine placement.
ENDORECON_HD void CoarseWeights(const ChunkShape& shape, const ChunkArrays& a, int r) {
  const std::size_t o = static_cast<std::size_t>(r) * shape.coarse;
  CompositeRay(a.sigma + o, a.color + 3 * o, a.s + o, a.delta + o, shape.coarse, a.weights + o);
  for (int j = 0; j < shape.coarse; ++j) a.coarse_s[o + j] = a.s[o + j];
}

// The fine samples, placed by the coarse weights with a uniform floor, replacing the coarse ones.
ENDORECON_HD void PlaceFineRay(const ChunkShape& shape, const ChunkArrays& a, int r) {
  const std::size_t c = static_cast<std::size_t>(r) * shape.coarse;
  PlaceSamples(
      a.rays[r], shape.box, shape.time, shape.fine,
      [&](float lo, float hi, float* s, float* delta) {
        AdaptiveSamples(a.coarse_s + c, a.weights + c, shape.coarse, lo, hi, shape.floor, shape.fine,
                        BinCentre{}, s, delta);
      },
      a.Slot(r, shape.fine));
}

// Folds dropout pass number `pass` (1 for the first) of sample i into its moments.
ENDORECON_HD void AddDropoutPass(const ChunkArrays& a, const DropoutArrays& d, int pass, float eps,
                                 std::size_t i) {
  AddPass(d.density[i], pass, a.sigma[i], field::VarianceFromLogVar(a.sigma_lv[i], eps));
  const float color_var = field::VarianceFromLogVar(a.color_lv[i], eps);
  for (int c = 0; c < 3; ++c) AddPass(d.color[3 * i + c], pass, a.color[3 * i + c], color_var);
}

// After K passes: sample i's density and colour become the pass means, and its variances are set.
// The head predicts one aleatoric colour variance for the three channels; the epistemic one is the
// mean over the channels of each channel's variance across passes.
ENDORECON_HD void FinishDropoutPasses(const ChunkArrays& a, const DropoutArrays& d, int passes,
                                      std::size_t i) {
  const McMoments<float>& density = d.density[i];
  const McMoments<float>* color = d.color + 3 * i;
  a.sigma[i] = density.mean;
  float color_epistemic = 0;
  for (int c = 0; c < 3; ++c) {
    a.color[3 * i + c] = color[c].mean;
    color_epistemic += Epistemic(color[c], passes) / 3.0f;
  }
  d.var_density[1][i] = Aleatoric(density, passes);
  d.var_density[2][i] = Epistemic(density, passes);
  d.var_color[1][i] = Aleatoric(color[0], passes);
  d.var_color[2][i] = color_epistemic;
  d.var_density[0][i] = d.var_density[1][i] + d.var_density[2][i];
  d.var_color[0][i] = d.var_color[1][i] + d.var_color[2][i];
}

// Ray r's colour (over the background), depth (the far plane where it is transparent), opacity and,
// with dropout passes (d.density not null), its ray scores with colour weight lambda.
ENDORECON_HD void FinishRay(const ChunkShape& shape, const ChunkArrays& a, const DropoutArrays& d,
                            float lambda, const PixelOutputs& out, int r) {
  const int m = shape.fine;
  const std::size_t o = static_cast<std::size_t>(r) * m;
  RayComposite<float> ray =
      CompositeRay(a.sigma + o, a.color + 3 * o, a.s + o, a.delta + o, m, a.weights + o);
  float learned[3];
  const float* background = shape.background;
  if (shape.background_params != nullptr) {
    float unit[3];
    scene::UnitDirection(a.rays[r].direction, unit);
    field::BackgroundSample(shape.background_params, unit, learned);
    background = learned;
  }
  AddBackground(ray, background);
  for (int c = 0; c < 3; ++c) out.rgb[3 * r + c] = ray.rgb[c];
  out.depth[r] = ray.depth + (1.0f - ray.opacity) * shape.far;
  out.opacity[r] = ray.opacity;
  if (d.density == nullptr) return;
  float* scores[3] = {out.uncertainty, out.aleatoric, out.epistemic};
  for (int i = 0; i < 3; ++i) {
    if (scores[i] != nullptr)
      scores[i][r] = RayScore(a.weights + o, d.var_density[i] + o, d.var_color[i] + o, m, lambda);
  }
}

}  // namespace endorecon::render
