#include "common/output_folder.h"

#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstring>
#include <span>
#include <string>
#include <system_error>

#include "common/clip_files.h"
#include "common/error.h"
#include "common/filesystem_failure.h"

namespace endorecon {
namespace {

namespace fs = std::filesystem;

using Names = std::span<const char* const>;

// The files that mark a folder as a run's results: written first, so an interrupted run is one too.
Names MarkersOf(ResultsKind kind) {
  static constexpr std::array<const char*, 2> kRun{"config.json", "metrics.json"};
  static constexpr std::array<const char*, 1> kViews{"render.json"};
  return kind == ResultsKind::kReconstruction ? Names(kRun) : Names(kViews);
}

// What a run writes (the results layout's names, docs/formats.md) but the files that mark the folder,
// which are written again first, and model/.
Names OutputsOf(ResultsKind kind) {
  static constexpr std::array<const char*, 15> kRun{
      "rgb",       "depth",     "uncertainty",  "error",       "pointcloud",
      "dicom",     "mesh.ply",  "mesh.obj",     "mesh.stl",    "video.mp4",
      "video.avi", "curve.svg", "metrics.json", "report.html", "recording.json"};
  static constexpr std::array<const char*, 5> kViews{"rgb", "depth", "uncertainty", "report.html",
                                                     "cameras.json"};
  return kind == ResultsKind::kReconstruction ? Names(kRun) : Names(kViews);
}

const char* NameOf(ResultsKind kind) {
  return kind == ResultsKind::kReconstruction ? "a reconstruction's results" : "a render's views";
}

bool HoldsResults(const fs::path& out, ResultsKind kind) {
  std::error_code error;
  for (const char* marker : MarkersOf(kind)) {
    if (fs::exists(out / marker, error)) return true;
  }
  return false;
}

// Whether `inner` is `outer` or lies inside it (both resolved as far as they exist).
bool IsOrInside(const fs::path& inner, const fs::path& outer) {
  std::error_code error;
  const fs::path a = fs::weakly_canonical(inner, error);
  if (error) return false;
  const fs::path b = fs::weakly_canonical(outer, error);
  if (error) return false;
  auto [end_b, end_a] = std::mismatch(b.begin(), b.end(), a.begin(), a.end());
  return end_b == b.end();
}

}  // namespace

// Checked before a run spends its time: a reconstruction into a read-only folder loaded the clip and
// then failed as "UNAVAILABLE: cannot write run configuration" (found 2026-12-07).
void RequireWritableFolder(const fs::path& folder, std::string_view what) {
  std::error_code error;
  fs::path at = fs::absolute(folder, error);
  if (error) return;
  struct stat info {};
  bool itself = true;  // `folder` exists (else an ancestor, where it would be made)
  while (::stat(at.c_str(), &info) != 0) {
    const int reason = errno;
    if (reason != ENOENT) {
      FailInvalid(std::string(what) + " " + folder.string() + " cannot be made or written: " + at.string() +
                  ": " + std::strerror(reason) + RunsAsNote(reason));
    }
    if (!at.has_relative_path()) return;
    at = at.parent_path();
    itself = false;
  }
  if (!S_ISDIR(info.st_mode)) return;  // a file: refused by the caller, or when the folder is made
  if (::access(at.c_str(), W_OK | X_OK) != 0) {
    const int reason = errno;
    FailInvalid(std::string(what) + " " + folder.string() + " cannot be " + (itself ? "written" : "made") +
                ": " + at.string() + ": " + std::strerror(reason) + RunsAsNote(reason));
  }
}

void CheckOutputFolder(const fs::path& out, const fs::path& input, std::string_view what, ResultsKind kind) {
  RequireWritableFolder(out);
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
  // An earlier run's results of this kind are replaced, as a rerun or a resume means to. The other
  // kind's are not: a render into a reconstruction's folder overwrote its report and first frames and
  // left the rest (found 2026-12-05).
  if (HoldsResults(out, kind)) return;
  const ResultsKind other =
      kind == ResultsKind::kRender ? ResultsKind::kReconstruction : ResultsKind::kRender;
  if (HoldsResults(out, other)) {
    FailInvalid("the output folder " + out.string() + " holds " + NameOf(other) + ", which " + NameOf(kind) +
                " would be mixed into; choose another output folder");
  }
  // Any other non-empty folder is someone's files, which results would be mixed into and partly
  // overwritten (`-o ~/Documents` was taken until 2026-12-05). Dot files (a desktop's .DS_Store, a
  // .gitignore) do not count, nor the input itself (a worker prepares a recording's clip into its
  // results folder, which ships it).
  for (fs::directory_iterator it(out, error), end; !error && it != end; it.increment(error)) {
    const std::string name = it->path().filename().string();
    std::error_code not_comparable;  // an input that is no file: then no entry is it
    if (name.starts_with(".") || fs::equivalent(it->path(), input, not_comparable)) continue;
    FailInvalid("the output folder " + out.string() + " holds other files (" + name +
                ", ...) and no earlier results: the results would be mixed in with them; choose an empty "
                "or new folder");
  }
}

void ClearEarlierResults(const fs::path& out, ResultsKind kind, std::initializer_list<fs::path> keep) {
  for (const char* name : OutputsOf(kind)) {
    const fs::path entry = out / name;
    std::error_code error;
    if (!fs::exists(fs::symlink_status(entry, error))) continue;
    if (std::any_of(keep.begin(), keep.end(),
                    [&](const fs::path& kept) { return !kept.empty() && IsOrInside(kept, entry); }))
      continue;
    fs::remove_all(entry, error);
    if (error) {
      Fail(ErrorCode::kUnavailable,
           "cannot remove the earlier run's " + entry.string() + ": " + error.message());
    }
  }
}

}  // namespace endorecon
