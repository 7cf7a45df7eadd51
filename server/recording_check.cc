#include "server/recording_check.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <stdlib.h>

#include <filesystem>
#include <optional>
#include <string_view>
#include <system_error>

#include "common/dicom/recording_header.h"
#include "common/dicom/recording_layout.h"
#include "common/dicom_file.h"
#include "common/error.h"
#include "common/prepare_flags.h"
#include "common/replace_all.h"

namespace endorecon::server {
namespace fs = std::filesystem;
namespace {

// A private folder of links to the stored blobs, named as the clip names its files: the worker's
// layout of the job's clip, without a copy. Removed when it goes out of scope.
class LinkedClip {
 public:
  LinkedClip() {
    std::string name = (fs::temp_directory_path() / "endorecon-recording-XXXXXX").string();
    if (::mkdtemp(name.data()) == nullptr)  // 0700: the file names may name a patient
      Fail(ErrorCode::kUnavailable, "cannot make a folder in " + fs::temp_directory_path().string());
    root_ = name;
  }
  ~LinkedClip() {
    std::error_code ignored;
    fs::remove_all(root_, ignored);
  }
  LinkedClip(const LinkedClip&) = delete;
  LinkedClip& operator=(const LinkedClip&) = delete;

  // The clip's files directly in its folder, where a recording's files lie and what tells a clip
  // folder from a recording (a clip's thousands of frames in images/ are not linked). False when the
  // store lacks a blob.
  bool Link(const v1::Manifest& clip, const BlobStore& blobs) {
    for (const auto& file : clip.files()) {
      if (file.path().find('/') != std::string::npos) continue;
      if (!blobs.Has(file.sha256())) return false;
      // Absolute: under a relative --data-dir (the default's) the links pointed nowhere from the
      // temporary folder, and no recording was checked (found 2026-12-07). A checked name (ValidateManifest).
      fs::create_symlink(fs::absolute(blobs.PathOf(file.sha256())), root_ / file.path());
    }
    return true;
  }
  const fs::path& root() const { return root_; }

 private:
  fs::path root_;
};

// The message with the folder's paths said as the clip names them: "rec/1.dcm: ..." for
// "/tmp/endorecon-recording-ab12cd/rec/1.dcm: ..."; the folder itself is the clip's one file (a
// recording submitted as a file), or "the recording".
std::string AsClipNames(std::string message, const fs::path& root, const v1::Manifest& clip) {
  const std::string folder = root.string();
  const std::string whole = clip.files_size() == 1 ? clip.files(0).path() : "the recording";
  return ReplaceAll(ReplaceAll(std::move(message), folder + "/", ""), folder, whole);
}

}  // namespace

void CheckRecording(const v1::Manifest& clip, const v1::RecordingOptions& options, const BlobStore& blobs) {
  std::optional<LinkedClip> linked;
  try {
    linked.emplace();
    if (!linked->Link(clip, blobs) || !dicom::HoldsDicom(linked->root())) return;
  } catch (const std::exception& e) {  // a full or unwritable temp folder: the worker checks it still
    spdlog::warn("a submitted recording is not checked before the queue: {}", e.what());
    return;
  }
  const FrameSize size = options.size().empty() ? FrameSize{} : ParseFrameSize(options.size());
  try {
    dicom::CheckRecordingHeader(linked->root(), dicom::ParseStereoLayout(options.stereo()),
                                ParseFrameRange(options.frames()), size);
  } catch (const Error& e) {
    throw Error(e.code(), AsClipNames(e.what(), linked->root(), clip));
  }
}

}  // namespace endorecon::server
