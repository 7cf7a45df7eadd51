#include "client/clip_check.h"

#include <optional>
#include <string>
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
    // An EndoNeRF clip's pose rows are checked as the loader checks them, and count its frames.
    std::vector<FrameFiles> frames =
        FindClipLayout(dir) == ClipLayout::kEndoNerf
            ? ListEndoNerfFrames(dir, ReadPoseRows(dir / "poses_bounds.npy").rows.size())
            : ListClipFrames(dir);
    const std::size_t clip_frames = frames.size();
    // gt/'s too: a damaged gt/depth/*.npy failed the job on a worker (found 2026-12-06).
    if (std::filesystem::is_directory(dir / "gt")) {
      for (FrameFiles& truth : ListGroundTruthFrames(dir / "gt", frames.size()))
        frames.push_back(std::move(truth));
    }
    // The frames' files share one size, as the loader requires (a mask of another size was found only
    // on a worker; 2026-12-06): told from their headers, the first image's setting it (a file whose
    // header does not say, a TIFF, is left to the worker). gt/'s are the worker's to compare.
    std::optional<ImageSize> clip_size;
    std::filesystem::path first;
    const auto check_size = [&](const std::filesystem::path& file) {
      const auto size = ImageSizeOf(file);
      if (!size) return;
      if (!clip_size) {
        clip_size = size;
        first = file;
      } else if (size->width != clip_size->width || size->height != clip_size->height) {
        FailInvalid(file.string() + ": size " + std::to_string(size->width) + "x" +
                    std::to_string(size->height) + " differs from the clip's " +
                    std::to_string(clip_size->width) + "x" + std::to_string(clip_size->height) + " (" +
                    first.string() + ")");
      }
    };
    for (std::size_t i = 0; i < frames.size(); ++i) {
      const FrameFiles& frame = frames[i];
      const bool of_the_clip = i < clip_frames;
      for (const auto* image : {&frame.image, &frame.tool_mask, &frame.eval_mask, &frame.right_image}) {
        if (image->empty()) continue;
        CheckImageBytes(*image);
        if (of_the_clip) check_size(*image);
      }
      if (frame.depth.empty()) continue;
      if (HasExtension(frame.depth, {".npy"})) {
        ReadNpy(frame.depth);
      } else {
        CheckImageBytes(frame.depth);
        if (of_the_clip) check_size(frame.depth);
      }
    }
  } catch (const Error& e) {
    Fail(e.code(), std::string(e.what()) + " (found before the upload: nothing was sent)");
  }
}

}  // namespace endorecon::client
