#include "client/recording_upload.h"

#include <string>
#include <tuple>
#include <vector>

#include "client/staging_folder.h"
#include "common/clip_files.h"
#include "common/error.h"
#include "common/file_read.h"
#include "common/image_bytes.h"

namespace endorecon::client {
namespace fs = std::filesystem;

namespace {

// A path's last name, a trailing separator or "." aside.
fs::path Named(const std::string& path) {
  std::error_code error;
  fs::path named = fs::absolute(path, error).lexically_normal();
  if (error) named = fs::path(path).lexically_normal();
  return named.has_filename() ? named : named.parent_path();
}

}  // namespace

std::string RecordingName(const PrepareFlags& flags) {
  if (!flags.left.empty() && !flags.right.empty()) {
    const fs::path left = Named(flags.left), right = Named(flags.right);
    if (left.parent_path() == right.parent_path() && left.parent_path().has_filename())
      return left.parent_path().filename().string();
    return left.filename().string() + " + " + right.filename().string();
  }
  const std::string& both = !flags.left.empty()           ? flags.left
                            : !flags.side_by_side.empty() ? flags.side_by_side
                                                          : flags.top_bottom;
  return Named(both).filename().string();
}

StagedRecording::StagedRecording(const PrepareFlags& flags) : flags_(flags) {
  CheckPrepareFlags(flags);
  dir_ = MakeStagingFolder("recording");
  const auto stage = [&](std::string& path, const std::string& name, const char* flag = nullptr) {
    if (!path.empty()) path = Stage(path, name, flag);
  };
  name_ = RecordingName(flags);
  stage(flags_.left, "left");
  stage(flags_.right, "right");
  stage(flags_.side_by_side, "side_by_side");
  stage(flags_.top_bottom, "top_bottom");
  if (flags_.calibration.size() == 1) stage(flags_.calibration[0], "calibration", "--calibration");
  if (flags_.calibration.size() == 2) {
    stage(flags_.calibration[0], "calibration_left", "--calibration");
    stage(flags_.calibration[1], "calibration_right", "--calibration");
  }
  stage(flags_.masks, "masks");
  stage(flags_.poses, "poses", "--poses");
}

StagedRecording::~StagedRecording() {
  std::error_code ignored;
  fs::remove_all(dir_, ignored);
}

std::string StagedRecording::Stage(const std::string& path, const std::string& name, const char* file_flag) {
  const fs::path source = fs::absolute(path);
  if (fs::is_directory(source)) {
    if (file_flag) FailInvalid(path + ": a folder, and " + file_flag + " takes a file");
    // Only a folder's frames go up (the worker reads nothing else of it): a folder named by mistake
    // (../../etc) must not send its files to the server.
    fs::create_directories(dir_ / name);
    int files = 0;
    for (const auto& entry : fs::directory_iterator(source)) {
      const std::string file = entry.path().filename().string();
      if (!entry.is_regular_file() || file.front() == '.' || !HasExtension(entry.path(), ImageExtensions()))
        continue;
      fs::create_symlink(entry.path(), dir_ / name / file);
      ++files;
    }
    if (files == 0)
      FailInvalid(path + ": the folder holds no image (frames as PNG, JPEG, BMP or TIFF files)");
    sources_[name + "/"] = fs::path(path).lexically_normal().string() + (path.back() == '/' ? "" : "/");
    return name;
  }
  // A FIFO: named as one (with what the flag takes), not as missing.
  RequireRegularFile(source, file_flag ? "file (" + std::string(file_flag) + " takes a file)"
                                       : "video file or folder of frames");
  if (!fs::is_regular_file(source)) Fail(ErrorCode::kNotFound, path + ": no such file or folder");
  const std::string staged = name + source.extension().string();
  fs::create_symlink(source, dir_ / staged);
  sources_[staged] = path;
  return staged;
}

void StagedRecording::CheckBeforeUpload() const {
  const auto frames_of = [&](const std::string& name) {
    std::vector<fs::path> files;
    if (!fs::is_directory(dir_ / name)) return files;
    for (const auto& entry : fs::directory_iterator(dir_ / name)) files.push_back(entry.path());
    return files;
  };
  const auto users = [&](const std::string& name) { return sources_.at(name + "/"); };
  const auto left = frames_of("left"), right = frames_of("right");
  // Eyes cut apart (--skip-left, --skip-right) may end apart too: the pairs end with the shorter.
  const bool cut_apart = flags_.skip_left > 0 || flags_.skip_right > 0;
  if (!cut_apart && !left.empty() && !right.empty() && left.size() != right.size()) {
    FailInvalid(users("right") + ": " + std::to_string(right.size()) + " frames while " + users("left") +
                " has " + std::to_string(left.size()) +
                " (both eyes' recordings must have the same length; if one eye's began earlier, pass "
                "--skip-left or --skip-right with the frames it began before the other: `endorecon-worker "
                "prepare` on these folders names them)");
  }
  // A skip that leaves a folder no frame is said before the upload, not by the job (found 2026-12-07).
  for (const auto& [name, count, skip, flag] :
       {std::tuple{"left", left.size(), flags_.skip_left, "--skip-left"},
        std::tuple{"right", right.size(), flags_.skip_right, "--skip-right"}}) {
    if (skip > 0 && count > 0 && static_cast<std::size_t>(skip) >= count) {
      FailInvalid(users(name) + ": it holds " + std::to_string(count) + " frame(s): none is left after the " +
                  std::to_string(skip) + " skipped (" + flag + " " + std::to_string(skip) + ")");
    }
  }
  if (!flags_.frames.empty()) return;  // frames outside the window are neither read nor checked
  for (const char* name : {"left", "right", "side_by_side", "top_bottom", "masks"}) {
    for (const fs::path& frame : frames_of(name)) {
      try {
        CheckImageBytes(frame);
      } catch (const Error& e) {
        // Named at the user's path, not at its link in the staging folder.
        std::string message = e.what();
        const std::string staged = frame.string();
        if (const auto at = message.find(staged); at != std::string::npos)
          message.replace(at, staged.size(), users(name) + frame.filename().string());
        Fail(e.code(), message);
      }
    }
  }
}

}  // namespace endorecon::client
