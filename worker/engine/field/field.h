// The neural field of the method: (x, t, d) -> (mu_sigma, l_sigma, mu_c, l_c).
//   x0 = x + dx(x, t)                          deformation to canonical space (skipped for static scenes)
//   f  = sum_i beta_t^(i) H_i(x0)              hash-grid ensemble, blended in time (or, for the
//                                              ablation's baseline, f = PE(x0): frequency_encoding.h)
//   (mu_sigma, l_sigma, geo) = MLP_dense(f)    density head
//   (mu_c, l_c) = MLP_color([geo, SH(d)])      colour head
// This file only composes the modules (each has its own forward and backward) and runs them in
// parallel over tiles of samples with TBB. The work split depends only on the batch size, and
// per-tile gradients are reduced in a fixed order, so results do not depend on the thread count.
#pragma once

#include <concepts>
#include <cstddef>
#include <cstdint>
#include <iosfwd>
#include <memory>
#include <string>
#include <vector>

#include "worker/engine/field/deformation.h"
#include "worker/engine/field/grid_ensemble.h"
#include "worker/engine/field/heads.h"
#include "worker/engine/train/param_group.h"

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

  // The paper's sizes: grids {8, 16, 32} x scales {1.4, 1.7, 1.9}, 16 levels x 8 features, 2^19 tables.
  static FieldConfig Paper();
  // Sized for >= 1 M training samples/s on 2 cores (see field.cc for the numbers behind it).
  static FieldConfig Cpu();
};

template <typename S>
struct SampleBatchT {
  int n = 0;
  const S* pos = nullptr;   // n x 3, normalised scene coordinates in [0, 1]^3
  const S* time = nullptr;  // n, in [0, 1]
  const S* dir = nullptr;   // n x 3, unit view directions
};

// Caller-owned output arrays.
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

// One group of parameters as the field owns it (any scalar type; Params() gives the optimiser's view).
template <typename S>
struct ParamBlock {
  std::string name;
  S* value = nullptr;
  S* grad = nullptr;
  std::size_t size = 0;
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

  // As Forward, but keeps nothing (for rendering): no batch-sized buffers are touched.
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

  // Groups "grid", "blend", "deform" (absent for a static scene), "density", "color".
  std::vector<ParamBlock<S>> Blocks();
  std::vector<train::ParamGroup> Params() requires std::same_as<S, float>;

  // Exact binary copy of every parameter. Load throws Error(kDataLoss) for a truncated stream or one
  // written by a field of another shape (the message says which group differs).
  void Save(std::ostream& out) const;
  void Load(std::istream& in);

  const FieldConfig& config() const { return config_; }
  // What was built and what was left out (levels above the resolution cap, deformation off), and the
  // parameter count of each group.
  std::string Describe() const;
  // Multiply-adds per sample of the two heads' forward passes (backward does twice as many).
  std::size_t head_macs_per_sample() const;

 private:
  struct Impl;  // the modules, parameters and buffers (field.cc)
  FieldConfig config_;
  std::unique_ptr<Impl> impl_;
};

using Field = FieldT<float>;
using SampleBatch = SampleBatchT<float>;
using FieldOutput = FieldOutputT<float>;
using FieldOutputGrad = FieldOutputGradT<float>;

}  // namespace endorecon::field
