// The training step on one GPU (train/step_backend.h): the clip's frames, depth priors, cameras,
// masks, occupancy grid and uncertainty map mirrored on the device; the batch on the device; the
// per-ray bodies of train/step_math.h in kernels; the field in a DeviceField and Adam in a DeviceAdam.
// Per step only the loss, the colour error and the gradient norms come back to the host.
// The occupancy rebuilds probe the device field's density (Densities: points up, densities down); the
// depth refinement pulls the parameters first (PullField) and renders on the GPU renderer
// (device_render.h); the tables they change are uploaded again (TablesChanged).
// A plain C++ header; defined in device_step.cu (builds with ENDORECON_WITH_CUDA only).
#pragma once

#include <memory>

#include "worker/engine/train/step_backend.h"

namespace endorecon::cuda {

class SharedFields;

// The factory for train::Trainer: steps on CUDA device `index` (as cudaSetDevice takes it), which the
// calling thread makes current, on the device copy of the host field in `shared` (the run's renderers
// read the same copy), or on a copy of its own when `shared` is null. Throws Error(kInvalidArgument)
// for a device that does not exist.
train::StepBackendFactory DeviceStepFactory(int index, std::shared_ptr<SharedFields> shared = nullptr);

}  // namespace endorecon::cuda
