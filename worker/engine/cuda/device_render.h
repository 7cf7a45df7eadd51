// Rendering chunks of pixels on one GPU (render/render_backend.h): the per-ray bodies of
// render/frame_math.h in kernels, the field in a DeviceField of its own (uploaded from the host field
// at each RenderPixels call's Begin, with the occupancy grid), the chunk's samples on the device; only
// the chunk's pixel list goes up and its per-pixel results come back. Same chunks and dropout seeds as
// the CPU backend, so the same pixels get the same masks. A plain C++ header; defined in
// device_render.cu (builds with ENDORECON_WITH_CUDA only).
#pragma once

#include "worker/engine/render/render_backend.h"

namespace endorecon::cuda {

// The factory for render::FrameRenderer: chunks on CUDA device `index` (as cudaSetDevice takes it),
// which the calling thread makes current. Throws Error(kInvalidArgument) for a device that does not exist.
render::RenderBackendFactory DeviceRenderFactory(int index);

}  // namespace endorecon::cuda
