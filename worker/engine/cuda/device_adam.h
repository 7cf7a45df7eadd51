// train::Adam on the GPU: the same per-group rates, decay, clipping and refusal of non-finite or
// overflowing gradients, over device parameter blocks, with the per-parameter update of
// train/adam_math.h in one kernel over every group. Only the groups' gradient norms come back to the
// host each step (two scalars a group, in one copy each). A plain C++ header; defined in device_adam.cu (builds with ENDORECON_WITH_CUDA).
#pragma once

#include <iosfwd>
#include <memory>
#include <vector>

#include "worker/engine/field/param_block.h"
#include "worker/engine/train/adam.h"

namespace endorecon::cuda {

class DeviceAdam {
 public:
  // `blocks`: device values and gradients (DeviceField::Blocks()).
  DeviceAdam(std::vector<field::ParamBlock<float>> blocks, train::AdamConfig config);
  ~DeviceAdam();

  // As train::Adam::Step.
  train::AdamStepReport Step(double progress);

  // The moments, in train::Adam's stream format (a checkpoint reads the same on either device).
  void Save(std::ostream& out) const;
  void Load(std::istream& in);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace endorecon::cuda
