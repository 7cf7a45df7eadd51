// A field::Mlp run by CUDA kernels on device arrays, with the Mlp's own layout of parameters and
// activations and the same dropout masks (field/mlp_math.h): one thread per (row, unit) for the layer
// products (the input gradient reads a layer's weights transposed in shared memory when they fit), the
// weight gradient summed over chunks of rows sized to fill the device, with atomics. A plain C++
// header; defined in device_mlp.cu (builds with ENDORECON_WITH_CUDA only). All pointers are device
// memory.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "worker/engine/field/mlp.h"
#include "worker/engine/field/module.h"

namespace endorecon::cuda {

class DeviceMlp {
 public:
  explicit DeviceMlp(const field::Mlp<float>& layout);

  int in_dim() const { return dims_.front(); }
  int out_dim() const { return dims_.back(); }
  int hidden_layers() const { return static_cast<int>(dims_.size()) - 2; }
  int hidden_dim(int k) const { return dims_[k + 1]; }
  // Floats of scratch Backward needs for n rows.
  std::size_t scratch_size(int n) const;

  // x: n x in_dim; hidden[k]: n x hidden_dim(k) (kept for Backward, a host array of device pointers);
  // y: n x out_dim.
  void Forward(const float* params, const float* x, int n, float* const* hidden, float* y,
               const field::DropoutPass& pass) const;
  // ADDS dL/dparams to dparams; writes dx (n x in_dim) when not null.
  void Backward(const float* params, const float* x, int n, float* const* hidden, const float* dy, float* dx,
                float* dparams, float* scratch, const field::DropoutPass& pass) const;

 private:
  std::vector<int> dims_;
  std::vector<std::size_t> w_offset_, b_offset_;
  double rate_;
  std::uint32_t stream_;
};

}  // namespace endorecon::cuda
