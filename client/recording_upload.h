// A raw stereo recording's files gathered under fixed names in a temporary folder (symbolic links,
// no copies), so `submit` uploads one folder (resumably, as a clip) and the job names its files
// the same way wherever it runs: left.<ext> or left/ (a folder's image files), right, side_by_side,
// top_bottom likewise, calibration.<ext> or calibration_left.<ext> and calibration_right.<ext>,
// masks.<ext> or masks/, poses.<ext>. The folder goes with the object.
#pragma once

#include <filesystem>
#include <map>
#include <string>

#include "common/prepare_flags.h"

namespace endorecon::client {

// A job's default name for a raw recording: for two eyes, the folder that holds both ("case7" for
// case7/left.mp4 and case7/right.mp4; such a job was named "left", found 2026-12-07), else the eyes'
// names joined ("l.mp4 + r.mp4"); for one file or folder of both eyes, its name.
std::string RecordingName(const PrepareFlags& flags);

class StagedRecording {
 public:
  // Checks the flags (CheckPrepareFlags); throws Error(kNotFound) naming a file that does not exist.
  explicit StagedRecording(const PrepareFlags& flags);
  ~StagedRecording();
  StagedRecording(const StagedRecording&) = delete;
  StagedRecording& operator=(const StagedRecording&) = delete;

  const std::filesystem::path& dir() const { return dir_; }
  // The flags with the staged names.
  const PrepareFlags& flags() const { return flags_; }
  // A name for the job (RecordingName).
  const std::string& name() const { return name_; }
  // Each staged name ("side_by_side.mp4", a folder's "left/") and the path as the user gave it.
  const std::map<std::string, std::string>& sources() const { return sources_; }

  // What the worker's preparation would refuse after the upload and a wait in the queue, as far as
  // that needs no decoding (its videos and calibration are the worker's to read): two folders of
  // frames as eyes must hold as many frames, and, for a whole recording (no --frames), every frame
  // of a folder (eyes, masks) is a whole PNG, JPEG, BMP or TIFF (common/image_bytes.h). A raw
  // recording with a truncated frame or an eye a frame short was uploaded, queued and failed on a
  // worker (found 2026-12-06). Throws Error (kInvalidArgument) naming the user's path.
  void CheckBeforeUpload() const;

 private:
  // Links `path` (a file, or a folder's visible image files) as `name` (+ the file's extension);
  // returns the staged name. With `file_flag` (the flag's name) a folder is refused: the flag takes
  // a file. A folder without images is refused naming the path as given.
  std::string Stage(const std::string& path, const std::string& name, const char* file_flag = nullptr);

  std::filesystem::path dir_;
  PrepareFlags flags_;
  std::string name_;
  std::map<std::string, std::string> sources_;
};

}  // namespace endorecon::client
