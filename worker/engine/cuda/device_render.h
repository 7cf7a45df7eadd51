// Rendering chunks of pixels on one GPU (render/render_backend.h): the per-ray bodies of
// render/frame_math.h in kernels, the chunk's samples on the device; only the chunk's pixel list goes
// up and its per-pixel results come back, and the occupancy grid at each RenderPixels call's Begin.
// The field is the run's device copy, which the training steps keep current (shared_fields.h), or,
// without one, a DeviceField of the renderer's own, uploaded from the host field at each Begin. Same
// chunks and dropout seeds as the CPU backend, so the same pixels get the same masks. A plain C++
// header; defined in device_render.cu (builds with ENDORECON_WITH_CUDA only).
#pragma once

#include <memory>

#include "worker/engine/render/render_backend.h"

namespace endorecon::cuda {

class SharedFields;

// The factory for render::FrameRenderer: chunks on CUDA device `index` (as cudaSetDevice takes it),
// which the calling thread makes current, with the device copy of the host field in `shared`, or a
// copy of its own when `shared` is null. Throws Error(kInvalidArgument) for a device that does not exist.
render::RenderBackendFactory DeviceRenderFactory(int index, std::shared_ptr<SharedFields> shared = nullptr);

}  // namespace endorecon::cuda
