// What a clip loader may accept, set by the caller (the reconstruct command, the service's limits).
#pragma once

#include <cstddef>

namespace endorecon::scene {

struct LoadOptions {
  std::size_t max_pixels_per_frame = std::size_t{4096} * 4096;  // larger frames: RESOURCE_EXHAUSTED
  bool force_static = false;  // mark the clip static (one time for all frames) whatever its layout says
};

}  // namespace endorecon::scene
