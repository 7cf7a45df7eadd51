// Where a command writes its results: never over what it reads.
#pragma once

#include <filesystem>
#include <string_view>

namespace endorecon {

// Throws Error(kInvalidArgument) naming both when `out` is the folder `input` itself (after symbolic
// links and "." / ".." are resolved): results written there would overwrite its files (a clip's
// depth/ by the rendered depth, a results folder's frames by other views). `what` names the input
// ("the clip", "the results folder"). Also refused: an `out` that is a file, a folder holding any
// clip (common/clip_files.h), or a non-empty folder that holds no earlier results (config.json,
// metrics.json, render.json or cameras.json; dot files aside). Nothing else is checked when either
// does not exist yet.
void CheckOutputFolder(const std::filesystem::path& out, const std::filesystem::path& input, std::string_view what);

}  // namespace endorecon
