// The neural field of the method: (x, t, d) -> (mu_sigma, l_sigma, mu_c, l_c).
//   x0 = x + dx(x, t)                          Deformation (left out for static scenes)
//   f  = sum_i beta_t^(i) H_i(x0)              TemporalBlend (beta_t), then GridEnsemble (H_i and the
//                                              sum) (or, for the ablation's baseline, f = PE(x0):
//                                              FrequencyEncoder)
//   (mu_sigma, l_sigma, geo) = MLP_dense(f)    DensityHead
//   (mu_c, l_c) = MLP_color([geo, SH(d)])      ColorHead
//   mu_c <- exp(a(t)) mu_c                     Exposure (per-frame camera gains; only when configured)
// and, per ray rather than per sample, bg(d): what a ray sees past its samples (Background; only
// when configured: FieldConfig::learned_background).
// A thin composition: each module (module.h) runs its own forward, backward and parallel loop over
// the batch; the field owns the parameter blocks and the activations that pass between them. Every
// module's split depends only on the batch size and partial gradients are reduced in a fixed order,
// so results do not depend on the thread count. Presets: field_config.h; saving and loading the
// parameters: field_state.h; the human-readable summary: field_description.h.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "worker/engine/field/background.h"
#include "worker/engine/field/deformation.h"
#include "worker/engine/field/exposure.h"
#include "worker/engine/field/field_config.h"
#include "worker/engine/field/frequency_encoder.h"
#include "worker/engine/field/grid_ensemble.h"
#include "worker/engine/field/heads.h"
#include "worker/engine/field/param_block.h"
#include "worker/engine/field/temporal_blend.h"

namespace endorecon::field {

template <typename S>
struct SampleBatchT {
  int n = 0;
  const S* pos = nullptr;   // n x 3, normalised scene coordinates in [0, 1]^3
  const S* time = nullptr;  // n, in [0, 1]
  const S* dir = nullptr;   // n x 3, unit view directions
};

// Caller-owned output arrays. Infer and Decode take a null rgb as "the density alone": the colour
// head is not run and rgb_logvar is not written (a renderer's coarse pass, an occupancy grid).
template <typename S>
struct FieldOutputT {
  S* sigma = nullptr;         // n, >= 0
  S* sigma_logvar = nullptr;  // n
  S* rgb = nullptr;           // n x 3, in (0, 1) (float rounds a saturated sigmoid to 0 or 1)
  S* rgb_logvar = nullptr;    // n
};

// dL/d(outputs), in the layout of FieldOutputT; a null pointer means zero.
template <typename S>
struct FieldOutputGradT {
  const S* sigma = nullptr;
  const S* sigma_logvar = nullptr;
  const S* rgb = nullptr;
  const S* rgb_logvar = nullptr;
};

template <typename S>
class FieldT {
 public:
  // Builds every module and initialises its parameters from `seed`. Throws Error(kInvalidArgument)
  // for a bad configuration (the message names the knob).
  FieldT(const FieldConfig& config, std::uint64_t seed);
  ~FieldT();
  FieldT(const FieldT&) = delete;
  FieldT& operator=(const FieldT&) = delete;

  // Evaluates every sample and keeps the activations Backward needs (until the next Forward).
  // Dropout in the heads when `dropout`, masks drawn from `dropout_seed`. Throws Error(kInvalidArgument)
  // for n < 0 or a missing array.
  void Forward(const SampleBatchT<S>& batch, FieldOutputT<S>& out, bool dropout, std::uint64_t dropout_seed);

  // As Forward, but keeps nothing (for rendering): the batch runs in segments through buffers of a
  // fixed size, and gives bit for bit what Forward gives.
  void Infer(const SampleBatchT<S>& batch, FieldOutputT<S>& out, bool dropout, std::uint64_t dropout_seed);

  // Infer in two halves, for K dropout passes over the same samples (Monte Carlo uncertainty): the
  // deterministic part (deformation, grids, temporal blend) once, then only the heads (where the
  // dropout is) per pass. Encode writes n x encoding_dim() values; Decode reads them and the batch's
  // directions. Decode(Encode(batch)) gives bit for bit what Infer(batch) gives with the same seed.
  int encoding_dim() const;
  void Encode(const SampleBatchT<S>& batch, S* encoding);
  void Decode(const S* encoding, const SampleBatchT<S>& batch, FieldOutputT<S>& out, bool dropout,
              std::uint64_t dropout_seed);

  // Adds dL/dparams to the gradients, for the batch of the last Forward (the same arrays).
  // Throws Error(kFailedPrecondition) when no Forward of that size preceded it.
  void Backward(const SampleBatchT<S>& batch, const FieldOutputGradT<S>& grad);

  void ZeroGrad();

  // The learned background (only with one: background() not null): rgb (n x 3) of n unit ray
  // directions (n x 3); BackgroundBackward adds dL/dparams from dL/d(rgb) (drgb, n x 3) given the
  // rgb of those directions. Throws Error(kFailedPrecondition) when the field has no background.
  void BackgroundRgb(int n, const S* dir, S* rgb);
  void BackgroundBackward(int n, const S* dir, const S* rgb, const S* drgb);

  // Blocks "grid", "blend" (both absent with the frequency encoding), "deform" (absent for a static
  // scene), "density", "color", "exposure" (absent without exposure knots), "background" (absent
  // without a learned background), in that order.
  std::vector<ParamBlock<S>> Blocks();
  std::vector<ParamBlock<const S>> Blocks() const;

  const FieldConfig& config() const { return config_; }
  // The modules, read only (descriptions, other backends). Null where the configuration leaves one out.
  const GridEnsemble<S>* grids() const;
  const TemporalBlend<S>* blend() const;
  const FrequencyEncoder<S>* frequency() const;
  const Deformation<S>* deformation() const;
  const DensityHead<S>& density() const;
  const ColorHead<S>& color() const;
  const Exposure<S>* exposure() const;
  const Background<S>* background() const;
  // Multiply-adds per sample of the two heads' forward passes (backward does twice as many).
  std::size_t head_macs_per_sample() const;

 private:
  struct Impl;  // the modules, parameters and activations (field.cc)
  FieldConfig config_;
  std::unique_ptr<Impl> impl_;
};

using Field = FieldT<float>;
using SampleBatch = SampleBatchT<float>;
using FieldOutput = FieldOutputT<float>;
using FieldOutputGrad = FieldOutputGradT<float>;

}  // namespace endorecon::field
