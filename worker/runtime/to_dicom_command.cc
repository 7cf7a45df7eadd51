// endorecon-worker to-dicom: a video or a folder of frames as a DICOM endoscopic recording, the way
// a hospital's recorder stores one: H.264 Video Endoscopic (OpenCV's FFmpeg encodes, DCMTK wraps),
// or multi-frame VL Endoscopic, uncompressed or JPEG. For a recording a user has as a video (the
// real one in ../shared/data/real/ is an MP4), and for demos and tests of the DICOM path.
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <memory>
#include <opencv2/core.hpp>
#include <opencv2/videoio.hpp>

#include "common/cli_checks.h"
#include "common/dicom/recording_writer.h"
#include "common/error.h"
#include "common/filesystem_failure.h"
#include "common/output_folder.h"
#include "worker/prepare/frame_source.h"
#include "worker/runtime/commands.h"

namespace endorecon::worker {
namespace fs = std::filesystem;
namespace {

struct ToDicomFlags {
  std::string frames, out, format = "h264", patient_id = "ANONYMOUS", patient_name, study_uid, uid_root;
  double fps = 0;  // 0: a video's own rate, 25 for a folder of images
  int series_number = 1;
};

// The recording's frame rate: asked for, or the source's (a video's from its first two frames'
// times; a folder's is kImageFolderFramePeriod's).
double FrameRate(double asked, const prepare::SourceFrame& first, const prepare::SourceFrame& second) {
  if (asked > 0) return asked;
  const double period = second.time_s - first.time_s;
  return period > 0 ? 1 / period : 1 / prepare::kImageFolderFramePeriod;
}

// H.264 (4:2:0) codes whole 2 x 2 blocks: FFmpeg cut an odd-sized frame to the even size below it
// while the DICOM header kept the odd one, a file endorecon then refused to read. Odd frames are
// padded by one row or column, repeating the edge.
cv::Mat EvenSized(const cv::Mat& image) {
  if (image.cols % 2 == 0 && image.rows % 2 == 0) return image;
  cv::Mat even;
  cv::copyMakeBorder(image, even, 0, image.rows % 2, 0, image.cols % 2, cv::BORDER_REPLICATE);
  return even;
}

// The MP4 the frames go through on their way into the DICOM file: removed however the writing ends.
struct TemporaryFile {
  fs::path path;
  ~TemporaryFile() {
    std::error_code ignored;
    fs::remove(path, ignored);
  }
};

// H.264: the frames re-encoded one at a time into an MP4 beside `out` (OpenCV's FFmpeg), which
// DCMTK then wraps; nothing but the current frame is held, so a long video fits in memory.
void WriteH264(prepare::FrameSource& source, double asked_fps, const dicom::RecordingHeader& header,
               const fs::path& out, int& frames, double& fps) {
  const TemporaryFile video{out.string() + ".mp4"};
  prepare::SourceFrame first, frame;
  if (!source.Next(first)) FailInvalid(source.name() + ": no frames");
  const bool more = source.Next(frame);
  fps = FrameRate(asked_fps, first, more ? frame : first);
  const cv::Size size = EvenSized(first.image).size();
  if (size != first.image.size()) {
    spdlog::warn("{}: frames of {}x{} are padded to {}x{} (H.264 codes even sizes), repeating the edge",
                 source.name(), first.image.cols, first.image.rows, size.width, size.height);
  }
  cv::VideoWriter writer(video.path.string(), cv::VideoWriter::fourcc('a', 'v', 'c', '1'), fps, size);
  if (!writer.isOpened()) {
    Fail(ErrorCode::kUnavailable, "cannot write the H.264 video " + video.path.string() +
                                      ": the installed FFmpeg cannot encode H.264 at " + std::to_string(fps) +
                                      " frames/s, or the folder is not writable");
  }
  writer.write(EvenSized(first.image));
  frames = 1;
  for (bool next = more; next; next = source.Next(frame)) {
    writer.write(EvenSized(frame.image));
    ++frames;
  }
  writer.release();
  dicom::WriteVideoEndoscopic(video.path, frames, size.width, size.height, fps, header, out);
}

// Multi-frame VL Endoscopic: every frame in one instance (uncompressed or JPEG), so all are held.
void WriteVl(prepare::FrameSource& source, double asked_fps, bool jpeg, const dicom::RecordingHeader& header,
             const fs::path& out, int& frames, double& fps) {
  std::vector<prepare::SourceFrame> read(1);
  if (!source.Next(read[0])) FailInvalid(source.name() + ": no frames");
  for (prepare::SourceFrame frame; source.Next(frame);) read.push_back(std::move(frame));
  fps = FrameRate(asked_fps, read[0], read[std::min<std::size_t>(1, read.size() - 1)]);
  std::vector<cv::Mat> images;
  std::vector<double> times;
  for (std::size_t i = 0; i < read.size(); ++i) {
    images.push_back(read[i].image);
    times.push_back(static_cast<double>(i) / fps);
  }
  dicom::WriteEndoscopicFrames(images, times, jpeg, header, out);
  frames = static_cast<int>(images.size());
}

int Run(const ToDicomFlags& flags) {
  if (fs::is_directory(flags.out)) {
    FailInvalid("-o " + flags.out + ": a folder; -o names the DICOM file to write (e.g. " +
                (fs::path(flags.out) / "recording.dcm").string() + ")");
  }
  // The input itself: `to-dicom same.mp4 -o same.mp4` wrote the DICOM file over the only copy of
  // the video (found 2026-12-07).
  std::error_code same_error;
  if (fs::exists(flags.out, same_error) && fs::equivalent(flags.out, flags.frames, same_error) &&
      !same_error) {
    FailInvalid("-o " + flags.out + " is the video it would be made from (" + flags.frames +
                "): writing it would destroy the recording; name another file (e.g. " +
                fs::path(flags.out).replace_extension(".dcm").string() + ")");
  }
  // The output's folder is made, as for every format (an H.264 recording's missing folder was
  // reported as FFmpeg unable to encode H.264).
  const fs::path out_dir = fs::path(flags.out).parent_path();
  std::error_code error;
  if (!out_dir.empty()) fs::create_directories(out_dir, error);
  if (error)
    FailInvalid("-o " + flags.out + ": cannot create its folder " + out_dir.string() + ": " +
                error.message() + RunsAsNote(error.value()));
  // One it may not write was said as FFmpeg unable to encode H.264 (found 2026-12-07).
  RequireWritableFolder(out_dir.empty() ? fs::path(".") : out_dir, "-o " + flags.out + ": its folder");
  const auto source = prepare::OpenFrameSource(flags.frames);
  dicom::RecordingHeader header;
  header.study =
      dicom::NewStudyContext(flags.patient_id, flags.patient_name, flags.study_uid, flags.uid_root);
  header.uid_root = flags.uid_root;
  header.series_number = flags.series_number;
  int frames = 0;
  double fps = 0;
  if (flags.format == "h264") {
    WriteH264(*source, flags.fps, header, flags.out, frames, fps);
  } else {
    WriteVl(*source, flags.fps, flags.format == "vl-jpeg", header, flags.out, frames, fps);
  }
  // The size written: H.264's even one (it said 161x91 of a recording holding 162x92; found 2026-12-07).
  const int width = source->frame_size().width, height = source->frame_size().height;
  const bool even = flags.format == "h264";
  spdlog::info("wrote {} ({} frames of {}x{} at {:.4g} frames/s, {}); study {}", flags.out, frames,
               even ? width + width % 2 : width, even ? height + height % 2 : height, fps, flags.format,
               header.study.study_instance_uid);
  return 0;
}

}  // namespace

Command AddToDicomCommand(CLI::App& app) {
  auto* cmd =
      app.add_subcommand("to-dicom", "write a video or a folder of frames as a DICOM endoscopic recording");
  auto flags = std::make_shared<ToDicomFlags>();
  cmd->add_option("frames", flags->frames,
                  "a video file (anything FFmpeg decodes), or a folder of frames (sorted by name), e.g. a "
                  "clip's images/")
      ->required();
  cmd->add_option("-o,--out", flags->out, "the DICOM file to write")->required();
  cmd->add_option("--format", flags->format,
                  "h264 (Video Endoscopic, MPEG-4 AVC/H.264), vl (multi-frame VL Endoscopic) or vl-jpeg")
      ->capture_default_str()
      ->check(CLI::IsMember({"h264", "vl", "vl-jpeg"}));
  cmd->add_option(
         "--fps", flags->fps,
         "the recording's frame rate, 0.01 to 1000: every frame is kept, frame N at N / FPS s (default: "
         "a video's own, 25 for a folder of frames; to keep fewer frames, reconstruct or submit --fps)")
      ->check(Within(0.01, 1000.0));
  cmd->add_option("--patient-id", flags->patient_id, "Patient ID")->capture_default_str();
  cmd->add_option("--patient-name", flags->patient_name, "Patient's Name (DICOM PN, e.g. Doe^Jane)");
  cmd->add_option("--study-uid", flags->study_uid, "Study Instance UID (default: a new one)");
  cmd->add_option("--uid-root", flags->uid_root, "root of new UIDs (default: 2.25 UUID-derived UIDs)");
  cmd->add_option("--series-number", flags->series_number,
                  "Series Number (a stereo pair as two series: the left eye's lower)")
      ->capture_default_str()
      ->check(CLI::Range(0, 99999));
  return [flags] { return Run(*flags); };
}

}  // namespace endorecon::worker
