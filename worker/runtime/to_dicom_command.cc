// endorecon-worker to-dicom: a folder of frames as a DICOM endoscopic recording, the way a
// hospital's recorder stores one: H.264 Video Endoscopic (OpenCV's FFmpeg encodes, DCMTK wraps),
// or multi-frame VL Endoscopic, uncompressed or JPEG. For demos and tests of the DICOM path.
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <memory>
#include <opencv2/videoio.hpp>

#include "common/dicom/recording_writer.h"
#include "common/error.h"
#include "worker/engine/scene/image_file.h"
#include "worker/runtime/commands.h"

namespace endorecon::worker {
namespace fs = std::filesystem;
namespace {

struct ToDicomFlags {
  std::string frames, out, format = "h264", patient_id = "ANONYMOUS", patient_name, study_uid, uid_root;
  double fps = 25;
};

std::vector<cv::Mat> ReadFrames(const fs::path& folder) {
  if (!fs::is_directory(folder)) Fail(ErrorCode::kNotFound, folder.string() + ": not a folder of frames");
  std::vector<fs::path> files;
  for (const auto& entry : fs::directory_iterator(folder)) {
    if (entry.is_regular_file() && entry.path().filename().string().front() != '.')
      files.push_back(entry.path());
  }
  std::sort(files.begin(), files.end());
  std::vector<cv::Mat> frames;
  for (const auto& file : files) {
    frames.push_back(scene::DecodeImageFileAsBgr8(file));
    if (frames.back().size() != frames.front().size())
      FailInvalid(file.string() + ": differs in size from the first frame");
  }
  if (frames.empty()) FailInvalid(folder.string() + ": no frames");
  return frames;
}

void WriteH264(const std::vector<cv::Mat>& frames, double fps, const dicom::RecordingHeader& header,
               const fs::path& out) {
  const fs::path video = out.string() + ".mp4";
  cv::VideoWriter writer(video.string(), cv::VideoWriter::fourcc('a', 'v', 'c', '1'), fps, frames[0].size());
  if (!writer.isOpened()) Fail(ErrorCode::kUnavailable, "the installed FFmpeg cannot encode H.264");
  for (const auto& frame : frames) writer.write(frame);
  writer.release();
  dicom::WriteVideoEndoscopic(video, static_cast<int>(frames.size()), frames[0].cols, frames[0].rows, fps,
                              header, out);
  fs::remove(video);
}

int Run(const ToDicomFlags& flags) {
  const auto frames = ReadFrames(flags.frames);
  dicom::RecordingHeader header;
  header.study =
      dicom::NewStudyContext(flags.patient_id, flags.patient_name, flags.study_uid, flags.uid_root);
  header.uid_root = flags.uid_root;
  if (flags.format == "h264") {
    WriteH264(frames, flags.fps, header, flags.out);
  } else {
    std::vector<double> times;
    for (std::size_t i = 0; i < frames.size(); ++i) times.push_back(static_cast<double>(i) / flags.fps);
    dicom::WriteEndoscopicFrames(frames, times, flags.format == "vl-jpeg", header, flags.out);
  }
  spdlog::info("wrote {} ({} frames of {}x{}, {}); study {}", flags.out, frames.size(), frames[0].cols,
               frames[0].rows, flags.format, header.study.study_instance_uid);
  return 0;
}

}  // namespace

Command AddToDicomCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand("to-dicom", "write a folder of frames as a DICOM endoscopic recording");
  auto flags = std::make_shared<ToDicomFlags>();
  cmd->add_option("frames", flags->frames, "folder of frames (sorted by name), e.g. a clip's images/")
      ->required();
  cmd->add_option("-o,--out", flags->out, "the DICOM file to write")->required();
  cmd->add_option("--format", flags->format,
                  "h264 (Video Endoscopic, MPEG-4 AVC/H.264), vl (multi-frame VL Endoscopic) or vl-jpeg")
      ->capture_default_str()
      ->check(CLI::IsMember({"h264", "vl", "vl-jpeg"}));
  cmd->add_option("--fps", flags->fps, "frames per second")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  cmd->add_option("--patient-id", flags->patient_id, "Patient ID")->capture_default_str();
  cmd->add_option("--patient-name", flags->patient_name, "Patient's Name (DICOM PN, e.g. Doe^Jane)");
  cmd->add_option("--study-uid", flags->study_uid, "Study Instance UID (default: a new one)");
  cmd->add_option("--uid-root", flags->uid_root, "root of new UIDs (default: 2.25 UUID-derived UIDs)");
  return [flags] { return Run(*flags); };
}

}  // namespace endorecon::worker
