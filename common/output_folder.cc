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
  // An earlier run's results (a run's config.json comes first, a render's render.json or cameras.json)
  // are written over, as a rerun or a resume means to; any other non-empty folder is someone's files,
  // which results would be mixed into and partly overwritten (`-o ~/Documents` was taken until
  // 2026-12-05). Dot files (a desktop's .DS_Store, a .gitignore) do not count, nor the input itself (a
  // worker prepares a recording's clip into its results folder, which ships it).
  for (const char* earlier : {"config.json", "metrics.json", "render.json", "cameras.json"}) {
    if (fs::exists(out / earlier, error)) return;
  }
  for (fs::directory_iterator it(out, error), end; !error && it != end; it.increment(error)) {
    const std::string name = it->path().filename().string();
    std::error_code not_comparable;  // an input that is no file: then no entry is it
    if (name.starts_with(".") || fs::equivalent(it->path(), input, not_comparable)) continue;
    FailInvalid("the output folder " + out.string() + " holds other files (" + name +
                ", ...) and no earlier results: the results would be mixed in with them; choose an empty "
                "or new folder");
  }
}

}  // namespace endorecon
