#include "client/recording_upload.h"

#include <unistd.h>

#include <random>

#include "common/error.h"

namespace endorecon::client {
namespace fs = std::filesystem;

StagedRecording::StagedRecording(const PrepareFlags& flags) : flags_(flags) {
  CheckPrepareFlags(flags);
  dir_ = fs::temp_directory_path() /
         ("endorecon-recording-" + std::to_string(::getpid()) + "-" + std::to_string(std::random_device{}()));
  fs::create_directories(dir_);
  const auto stage = [&](std::string& path, const std::string& name) {
    if (!path.empty()) path = Stage(path, name);
  };
  name_ = fs::path(!flags.left.empty()           ? flags.left
                   : !flags.side_by_side.empty() ? flags.side_by_side
                                                 : flags.top_bottom)
              .lexically_normal()
              .filename()
              .string();
  stage(flags_.left, "left");
  stage(flags_.right, "right");
  stage(flags_.side_by_side, "side_by_side");
  stage(flags_.top_bottom, "top_bottom");
  if (flags_.calibration.size() == 1) stage(flags_.calibration[0], "calibration");
  if (flags_.calibration.size() == 2) {
    stage(flags_.calibration[0], "calibration_left");
    stage(flags_.calibration[1], "calibration_right");
  }
  stage(flags_.masks, "masks");
  stage(flags_.poses, "poses");
}

StagedRecording::~StagedRecording() {
  std::error_code ignored;
  fs::remove_all(dir_, ignored);
}

std::string StagedRecording::Stage(const std::string& path, const std::string& name) {
  const fs::path source = fs::absolute(path);
  if (fs::is_directory(source)) {
    fs::create_directories(dir_ / name);
    int files = 0;
    for (const auto& entry : fs::directory_iterator(source)) {
      const std::string file = entry.path().filename().string();
      if (!entry.is_regular_file() || file.front() == '.') continue;
      fs::create_symlink(entry.path(), dir_ / name / file);
      ++files;
    }
    if (files == 0) FailInvalid(path + ": the folder holds no file");
    sources_[name + "/"] = fs::path(path).lexically_normal().string() + (path.back() == '/' ? "" : "/");
    return name;
  }
  if (!fs::is_regular_file(source)) Fail(ErrorCode::kNotFound, path + ": no such file or folder");
  const std::string staged = name + source.extension().string();
  fs::create_symlink(source, dir_ / staged);
  sources_[staged] = path;
  return staged;
}

}  // namespace endorecon::client
