#include "common/manifest.h"

#include <sys/stat.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <limits>
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "common/error.h"
#include "common/file_read.h"
#include "common/safe_path.h"
#include "common/sha256.h"
#include "common/transport_security.h"

namespace endorecon {
namespace fs = std::filesystem;
namespace {

using FolderId = std::pair<dev_t, ino_t>;

FolderId IdOfFolder(const fs::path& dir) {
  struct stat info {};
  if (::stat(dir.c_str(), &info) != 0)
    FailInvalid(dir.string() + ": cannot read it (" + std::strerror(errno) + ")");
  return {info.st_dev, info.st_ino};
}

}  // namespace

v1::Manifest ListingOfDirectory(const fs::path& dir) {
  std::error_code error;
  if (!fs::exists(dir, error)) Fail(ErrorCode::kNotFound, dir.string() + ": no such file or folder");
  if (!fs::is_directory(dir, error)) {
    RequireRegularFile(dir, "clip folder");  // a FIFO, a socket, a device: named as what they are
    FailInvalid(dir.string() + ": a file, not a clip folder");
  }
  std::vector<fs::path> files;
  // Linked folders are followed (their files are the clip's); an entry that is neither a folder nor a
  // regular file (a broken or looping link, a pipe, a socket) is named: skipped, the clip would
  // arrive without it. A linked folder that leads back to one it is in is named too: followed, it
  // listed the clip again under ever longer names until the system's limit on links.
  std::vector<FolderId> open_folders{IdOfFolder(dir)};  // [k]: the folder that holds the entries at depth k
  try {
    for (auto it = fs::recursive_directory_iterator(dir, fs::directory_options::follow_directory_symlink);
         it != fs::recursive_directory_iterator(); ++it) {
      const auto& entry = *it;
      std::error_code error;
      if (entry.is_directory(error)) {
        const FolderId id = IdOfFolder(entry.path());
        open_folders.resize(static_cast<std::size_t>(it.depth()) + 1);
        const auto ancestor = std::find(open_folders.begin(), open_folders.end(), id);
        if (ancestor != open_folders.end()) {
          const fs::path target = fs::read_symlink(entry.path(), error);
          FailInvalid(entry.path().string() +
                      (error ? std::string() : " (a link to " + target.string() + ")") +
                      ": leads back to a folder it is in, so the clip would hold itself; remove the link");
        }
        open_folders.push_back(id);
        continue;
      }
      if (!entry.is_regular_file(error)) {
        FailInvalid(entry.path().string() + ": not a regular file (" +
                    (error ? error.message() : std::string("a broken link, a pipe, a socket or a device")) +
                    "); remove it or replace it by the file");
      }
      files.push_back(entry.path());
    }
  } catch (const fs::filesystem_error& e) {
    FailInvalid(e.path1().string() + ": cannot read it (" + e.code().message() + ")");
  }
  if (files.empty()) FailInvalid("no files under " + dir.string());
  return ListingOfFiles(dir, std::move(files));
}

v1::Manifest ListingOfFiles(const fs::path& dir, std::vector<fs::path> files) {
  std::sort(files.begin(), files.end());
  v1::Manifest manifest;
  for (const auto& file : files) {
    auto* entry = manifest.add_files();
    // Lexically: a symbolic link under `dir` (a staged recording) keeps its own name.
    const std::string relative = file.lexically_relative(dir).generic_string();
    try {
      CheckRelativePath(relative);  // what the server would refuse (a name that is not UTF-8), named here
    } catch (const Error& e) {
      FailInvalid(dir.string() + ": " + e.what());
    }
    entry->set_path(relative);
    entry->set_size(static_cast<std::int64_t>(fs::file_size(file)));
  }
  return manifest;
}

void AddDigests(const fs::path& root, v1::Manifest& manifest) {
  for (auto& entry : *manifest.mutable_files()) entry.set_sha256(Sha256File(root / entry.path()));
}

v1::Manifest ManifestOfDirectory(const fs::path& dir) {
  v1::Manifest manifest = ListingOfDirectory(dir);
  AddDigests(dir, manifest);
  return manifest;
}

bool IsSizesOnly(const v1::Manifest& manifest) {
  return manifest.files_size() > 0 && std::all_of(manifest.files().begin(), manifest.files().end(),
                                                  [](const v1::FileEntry& f) { return f.sha256().empty(); });
}

bool IsSha256Hex(std::string_view text) {
  return text.size() == 64 && std::all_of(text.begin(), text.end(), [](char c) {
           return (c >= '0' && c <= '9') || (c >= 'a' && c <= 'f');
         });
}

void ValidateManifest(const v1::Manifest& manifest, bool sizes_only) {
  if (manifest.files_size() == 0) FailInvalid("the manifest lists no files");
  std::set<std::string> seen;
  for (const auto& file : manifest.files()) {
    CheckRelativePath(file.path());
    if (!seen.insert(file.path()).second) FailInvalid("file '" + file.path() + "' is listed twice");
    if (file.size() < 0)
      FailInvalid("file '" + file.path() + "' has negative size " + std::to_string(file.size()));
    if (file.size() > kMaxFileBytes) {
      FailInvalid("file '" + file.path() + "' has size " + std::to_string(file.size()) + ", over the " +
                  std::to_string(kMaxFileBytes) + " bytes (1 PiB) any file may have");
    }
    const auto& digest = file.sha256();
    if (sizes_only && digest.empty()) continue;
    if (!IsSha256Hex(digest))
      FailInvalid("file '" + file.path() + "' has sha256 '" + digest + "', not 64 lowercase hex digits");
  }
}

std::int64_t TotalBytes(const v1::Manifest& manifest) {
  std::int64_t total = 0;
  for (const auto& file : manifest.files()) {
    // Saturates: a sum past the largest number is over every limit (it once wrapped to a negative
    // total that passed the size limit, the free-space check and the quota).
    if (__builtin_add_overflow(total, std::max<std::int64_t>(file.size(), 0), &total))
      return std::numeric_limits<std::int64_t>::max();
  }
  return total;
}

std::string LargestFileNote(const v1::Manifest& manifest) {
  const auto largest = std::max_element(manifest.files().begin(), manifest.files().end(),
                                        [](const auto& a, const auto& b) { return a.size() < b.size(); });
  if (largest == manifest.files().end()) return "";
  return " (its largest file: " + largest->path() + ", " + std::to_string(largest->size()) + " bytes)";
}

std::size_t MostManifestBytes() { return std::size_t(kMaxMessageBytes) - 64 * 1024; }

bool WritesUncertaintyMaps(const nlohmann::json& config) {
  return !(config.is_object() && config.contains("mc_passes") && config["mc_passes"] == 0);
}

void CheckResultsFit(std::size_t frames, bool uncertainty, std::size_t clip_manifest_bytes,
                     const std::string& where) {
  const std::size_t per_frame =
      uncertainty ? kResultManifestBytesPerFrame : kResultManifestBytesPerFrameWithoutUncertainty;
  const std::size_t results = frames * per_frame;
  if (clip_manifest_bytes + results <= MostManifestBytes()) return;
  // The clip's manifest grows with its frames too: how many frames of this clip's kind fit.
  const double clip_per_frame = frames > 0 ? double(clip_manifest_bytes) / double(frames) : 0.0;
  const auto fit = [&](std::size_t results_per_frame) {
    return std::to_string(
        std::size_t(double(MostManifestBytes()) / (double(results_per_frame) + clip_per_frame)));
  };
  FailInvalid(where + ": " + std::to_string(frames) +
              " frames: their results would take a manifest of about " + std::to_string(results) +
              " bytes, and with the clip's (" + std::to_string(clip_manifest_bytes) +
              ") more than the service's messages carry (" + std::to_string(MostManifestBytes()) +
              "): the job could not hand them back, nor `status` and `fetch` show them. At most about " +
              fit(kResultManifestBytesPerFrame) + " frames of this clip fit with uncertainty maps, " +
              fit(kResultManifestBytesPerFrameWithoutUncertainty) +
              " without (config mc_passes 0). Choose fewer frames (submit's --frames START:END:STEP), or "
              "reconstruct "
              "the clip on one machine (endorecon-worker reconstruct)");
}

}  // namespace endorecon
