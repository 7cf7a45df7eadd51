// A clip folder's frames picked by a frame range (LoadOptions::frames), for each of its loaders.
#pragma once

#include <cstddef>
#include <string>
#include <utility>
#include <vector>

#include "common/prepare_flags.h"

namespace endorecon::scene {

// The frames `range` picks of a clip folder's `count`, in order. Throws Error(kInvalidArgument)
// naming `where` and the range when it picks none.
inline std::vector<int> PickFrames(const FrameRange& range, std::size_t count, const std::string& where) {
  return range.PickedOf(static_cast<int>(count), where + ": ", "the clip's");
}

// Keeps the items at `picked` (in that order) of one entry a frame.
template <class T>
void KeepPicked(const std::vector<int>& picked, std::vector<T>& items) {
  std::vector<T> kept;
  kept.reserve(picked.size());
  for (const int frame : picked) kept.push_back(std::move(items[static_cast<std::size_t>(frame)]));
  items = std::move(kept);
}

}  // namespace endorecon::scene
