#include "client/recording_upload.h"

#include "client/staging_folder.h"
#include "common/clip_files.h"
#include "common/error.h"
#include "common/file_read.h"

namespace endorecon::client {
namespace fs = std::filesystem;

StagedRecording::StagedRecording(const PrepareFlags& flags) : flags_(flags) {
  CheckPrepareFlags(flags);
  dir_ = MakeStagingFolder("recording");
  const auto stage = [&](std::string& path, const std::string& name, const char* flag = nullptr) {
    if (!path.empty()) path = Stage(path, name, flag);
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
  RequireRegularFile(source, "video file or folder of frames");  // a FIFO: named as one, not as missing
  if (!fs::is_regular_file(source)) Fail(ErrorCode::kNotFound, path + ": no such file or folder");
  const std::string staged = name + source.extension().string();
  fs::create_symlink(source, dir_ / staged);
  sources_[staged] = path;
  return staged;
}

}  // namespace endorecon::client
