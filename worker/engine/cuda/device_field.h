// A field (field/field.h) mirrored on the GPU: the same modules, parameter blocks and outputs, computed
// by CUDA kernels that are thin loops over the field's ENDORECON_HD per-sample functions
// (deformation_math.h, hash_math.h, blend_math.h, heads_math.h, mlp_math.h) and DeviceMlp. The host
// field gives the layout and is the parameters' home for checkpoints: Upload copies its parameters to
// the device, Download copies them back (a checkpoint written from either is the same file, so a run
// moves between a GPU and a CPU worker). A plain C++ header; defined in device_field.cu (builds with
// ENDORECON_WITH_CUDA only). Every pointer in batches and outputs is device memory; one call at a time.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "worker/engine/field/field.h"
#include "worker/engine/field/param_block.h"

namespace endorecon::cuda {

class StepPhases;

class DeviceField {
 public:
  // Allocates the device parameters and gradients and uploads the host field's values; `host` must
  // outlive this object. Throws Error(kResourceExhausted) when the device memory does not suffice.
  explicit DeviceField(field::Field& host);
  ~DeviceField();
  DeviceField(const DeviceField&) = delete;
  DeviceField& operator=(const DeviceField&) = delete;

  void Upload();    // host parameters -> device
  void Download();  // device parameters -> host (for checkpoints, models and host-side rendering)

  // As field::Field's, on device arrays.
  void Forward(const field::SampleBatch& batch, field::FieldOutput& out, bool dropout,
               std::uint64_t dropout_seed);
  void Infer(const field::SampleBatch& batch, field::FieldOutput& out, bool dropout,
             std::uint64_t dropout_seed);
  int encoding_dim() const;
  void Encode(const field::SampleBatch& batch, float* encoding);
  void Decode(const float* encoding, const field::SampleBatch& batch, field::FieldOutput& out, bool dropout,
              std::uint64_t dropout_seed);
  void Backward(const field::SampleBatch& batch, const field::FieldOutputGrad& grad);
  // As field::Field's BackgroundBackward (the field must have a learned background).
  void BackgroundBackward(int n, const float* dir, const float* rgb, const float* drgb);
  void ZeroGrad();
  // Marks the modules' phases of the passes that follow in `phases` (step_phases.h; nullptr: none).
  void SetPhases(StepPhases* phases);

  // The device blocks (values and gradients), in the host field's order and names.
  std::vector<field::ParamBlock<float>> Blocks();
  field::Field& host() { return host_; }

  struct Impl;  // the layouts, device blocks and buffers (device_field.cu)

 private:
  field::Field& host_;
  std::unique_ptr<Impl> impl_;
};

}  // namespace endorecon::cuda
