#include "worker/engine/scene/frame_pick.h"

#include "common/error.h"

namespace endorecon::scene {

std::vector<int> PickFrames(const FrameRange& range, std::size_t count, const std::string& where) {
  std::vector<int> picked = range.Of(static_cast<int>(count));
  if (picked.empty()) {
    FailInvalid(where + ": --frames " + range.ToString() + " picks none of the clip's " + std::to_string(count) +
                " frames (START:END:STEP counts them from 0, END exclusive)");
  }
  return picked;
}

}  // namespace endorecon::scene
