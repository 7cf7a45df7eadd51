#include "common/output_folder.h"

#include <string>
#include <system_error>

#include "common/clip_files.h"
#include "common/error.h"

namespace endorecon {

void CheckOutputFolder(const std::filesystem::path& out, const std::filesystem::path& input, std::string_view what) {
  namespace fs = std::filesystem;
  std::error_code error;
  if (!fs::exists(out, error)) return;
  if (!fs::is_directory(out, error))
    FailInvalid("the output folder " + out.string() + " is a file; choose a folder (it is made if missing)");
  if (fs::is_directory(input, error) && fs::equivalent(out, input, error) && !error) {
    FailInvalid("the output folder " + out.string() + " is " + std::string(what) + " (" + input.string() +
                ") itself: writing there would overwrite its files; choose another output folder");
  }
  // Any clip, not only the input: `render -o CLIP` wrote its depth maps over the clip's (found
  // 2026-12-05).
  if (FindClipLayout(out)) {
    FailInvalid("the output folder " + out.string() +
                " holds a clip (transforms.json or poses_bounds.npy): writing there would overwrite its "
                "files; choose another output folder");
  }
}

}  // namespace endorecon
