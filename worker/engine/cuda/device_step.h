// The training step on one GPU (train/step_backend.h): the clip's frames, depth priors, cameras,
// masks, occupancy grid and uncertainty map mirrored on the device; the batch on the device; the
// per-ray bodies of train/step_math.h in kernels; the field in a DeviceField and Adam in a DeviceAdam.
// Per step only the loss, the colour error and the gradient norms come back to the host.
// The occupancy rebuilds probe the device field's density (Densities: points up, densities down); the
// depth refinement pulls the parameters first (PullField) and renders on the GPU renderer
// (device_render.h); the tables they change are uploaded again (TablesChanged).
// A plain C++ header; defined in device_step.cu (builds with ENDORECON_WITH_CUDA only).
#pragma once

#include "worker/engine/train/step_backend.h"

namespace endorecon::cuda {

// The factory for train::Trainer: steps on CUDA device `index` (as cudaSetDevice takes it), which the
// calling thread makes current. Throws Error(kInvalidArgument) for a device that does not exist.
train::StepBackendFactory DeviceStepFactory(int index);

}  // namespace endorecon::cuda
