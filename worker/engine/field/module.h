// The face every trainable piece of the field shows (tiny-cuda-nn's lesson). A module object holds its
// shape and its own scratch, never its parameters: parameters, gradients and activations are caller
// arrays, so a field keeps one block per group and a GPU backend can run the same layouts on device
// memory. Every module M<S> (S = float, or double for the gradient checks) has
//
//   std::size_t param_count() const;               the size of its parameter block
//   void Init(S* params, std::uint64_t seed) const; initial values, a pure function of the seed
//   void Forward(const S* params, const Inputs& in, const Outputs& out, const DropoutPass& pass);
//   void Backward(const S* params, const Inputs& in, const Outputs& out, const OutputGrads& grad,
//                 S* dparams, const InputGrads& din, const DropoutPass& pass);
//
// over a batch of in.n samples in batch-major arrays (row i of an array of width w at i * w).
// Forward fills every array of Outputs, the activations Backward needs among them. Backward reads the
// Outputs of a Forward with the same inputs and pass, ADDS dL/dparams to dparams and WRITES the input
// gradients din asks for (a null pointer: not wanted); a null gradient in OutputGrads means zero.
// Each module runs its own parallel loop over the batch, split by the batch size only, with per-task
// partial gradients added in task order, so results never depend on the thread count. Forward keeps
// nothing in the module, so calls on different rows may run at once (the field runs its segments in
// parallel); Backward uses the module's own scratch: one Backward at a time per module object.
#pragma once

#include <concepts>
#include <cstddef>
#include <cstdint>

namespace endorecon::field {

// Dropout of one forward pass: `on` switches it for the pass; the masks are a pure function of
// (seed, the network's stream, layer, first_row + row, unit) (dropout.h), so a batch split into
// parts (first_row = the part's first row in the whole pass) draws the masks of the whole.
struct DropoutPass {
  bool on = false;
  std::uint64_t seed = 0;
  std::uint32_t first_row = 0;
};

template <typename M, typename S>
concept TrainableModule = requires(M& m, const M& cm, const S* params, S* grads, std::uint64_t seed,
                                   const typename M::Inputs& in, const typename M::Outputs& out,
                                   const typename M::OutputGrads& grad, const typename M::InputGrads& din,
                                   const DropoutPass& pass) {
  { cm.param_count() } -> std::same_as<std::size_t>;
  cm.Init(grads, seed);
  m.Forward(params, in, out, pass);
  m.Backward(params, in, out, grad, grads, din, pass);
  { in.n } -> std::convertible_to<int>;
};

}  // namespace endorecon::field
