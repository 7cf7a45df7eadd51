// Where a command writes its results: never over what it reads, never into someone's files, and never
// beside an earlier run's files that no longer match.
#pragma once

#include <filesystem>
#include <initializer_list>
#include <string_view>

namespace endorecon {

// Throws Error(kInvalidArgument) when this user cannot write into `folder` or, where it does not exist
// yet, make it (the nearest folder that exists decides): `what` and the folder, the folder that
// refused, the system's reason and the user the command runs as.
void RequireWritableFolder(const std::filesystem::path& folder, std::string_view what = "the output folder");

// What a command writes: a reconstruction's results (`reconstruct`, marked by its config.json or
// metrics.json) or a render of new cameras (`render`, marked by its render.json).
enum class ResultsKind { kReconstruction, kRender };

// Throws Error(kInvalidArgument) naming both when `out` is the folder `input` itself (after symbolic
// links and "." / ".." are resolved): results written there would overwrite its files (a clip's
// depth/ by the rendered depth, a results folder's frames by other views). `what` names the input
// ("the clip", "the results folder"). Also refused: an `out` that is a file, a folder holding any
// clip (common/clip_files.h), a folder holding the other kind's results, or a non-empty folder that
// holds no earlier results of `kind` (dot files and the input aside), and one this user cannot write
// or make (the nearest folder that exists decides). Nothing else is checked when either does not exist
// yet.
void CheckOutputFolder(const std::filesystem::path& out, const std::filesystem::path& input,
                       std::string_view what, ResultsKind kind);

// Removes what an earlier run of `kind` wrote into `out` (its frames, maps, meshes, DICOM, report:
// the results layout's names, docs/formats.md), so that a rerun leaves no stale file beside its own (a
// run without uncertainty kept the last one's maps, and its dicom/ described another model). The
// model/ folder stays (a resume reads its checkpoint; a run writes its model.bin again), and so does
// any entry that is or holds a path of `keep` (the input, a checkpoint to resume from), and anything
// else in `out`. Call after CheckOutputFolder.
void ClearEarlierResults(const std::filesystem::path& out, ResultsKind kind,
                         std::initializer_list<std::filesystem::path> keep);

}  // namespace endorecon
