#include "client/clip_check.h"

#include <utility>
#include <vector>

#include "common/clip_files.h"
#include "common/error.h"
#include "common/image_bytes.h"
#include "common/npy.h"
#include "common/pose_rows.h"

namespace endorecon::client {

void CheckClipBeforeUpload(const std::filesystem::path& dir) {
  try {
    std::vector<FrameFiles> frames = ListClipFrames(dir);
    if (FindClipLayout(dir) == ClipLayout::kEndoNerf) ReadPoseRows(dir / "poses_bounds.npy");
    // gt/'s too: a damaged gt/depth/*.npy failed the job on a worker (found 2026-12-06).
    if (std::filesystem::is_directory(dir / "gt")) {
      for (FrameFiles& truth : ListGroundTruthFrames(dir / "gt", frames.size()))
        frames.push_back(std::move(truth));
    }
    for (const FrameFiles& frame : frames) {
      for (const auto* image : {&frame.image, &frame.tool_mask, &frame.eval_mask, &frame.right_image}) {
        if (!image->empty()) CheckImageBytes(*image);
      }
      if (frame.depth.empty()) continue;
      if (HasExtension(frame.depth, {".npy"})) {
        ReadNpy(frame.depth);
      } else {
        CheckImageBytes(frame.depth);
      }
    }
  } catch (const Error& e) {
    Fail(e.code(), std::string(e.what()) + " (found before the upload: nothing was sent)");
  }
}

}  // namespace endorecon::client
