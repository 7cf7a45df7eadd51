// A clip folder cut to the frames --frames picks, for `submit` to upload those alone (a long clip's
// 10,000 frames went up for the 500 picked): a temporary folder holding the clip's layout file cut
// to them (poses_bounds.npy's rows, or transforms.json's "frames"), its stereo.json, and links to
// the picked frames' files (images, depth, masks, right eye, gt/) at their paths in the clip. The
// worker loads it as a clip cut by hand, which is what `reconstruct --frames` loads
// (docs/formats.md, "Some of the frames"). Removed with the object.
#pragma once

#include <cstddef>
#include <filesystem>
#include <string>

#include "common/prepare_flags.h"

namespace endorecon::client {

class StagedClipCut {
 public:
  // Throws Error(kInvalidArgument) naming the clip when `frames` picks none of its frames, or as the
  // clip's listing (ListClipFrames) does.
  StagedClipCut(const std::filesystem::path& clip, const FrameRange& frames);
  ~StagedClipCut();
  StagedClipCut(const StagedClipCut&) = delete;
  StagedClipCut& operator=(const StagedClipCut&) = delete;

  const std::filesystem::path& dir() const { return dir_; }
  std::size_t picked() const { return picked_; }
  std::size_t total() const { return total_; }
  // `text` (a message about the staged folder's files) naming the clip's own files instead.
  std::string InClip(std::string text) const;

 private:
  std::filesystem::path clip_;  // absolute
  std::string given_;           // as the user gave it, for messages
  std::filesystem::path dir_;
  std::size_t picked_ = 0;
  std::size_t total_ = 0;
};

}  // namespace endorecon::client
