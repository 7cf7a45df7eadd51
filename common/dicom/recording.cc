#include "common/dicom/recording.h"

#include <dcmtk/dcmdata/dcpixseq.h>
#include <dcmtk/dcmdata/dcpxitem.h>
#include <dcmtk/dcmdata/dcrledrg.h>
#include <dcmtk/dcmdata/dctk.h>
#include <dcmtk/dcmimage/diregist.h>
#include <dcmtk/dcmimgle/dcmimage.h>
#include <dcmtk/dcmjpeg/djdecode.h>
#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cmath>
#include <fstream>
#include <map>
#include <memory>
#include <mutex>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include "common/dicom/dataset_access.h"
#include "common/dicom/recording_header.h"
#include "common/dicom/recording_series.h"
#include "common/error.h"
#include "common/jpeg_header.h"

namespace endorecon::dicom {
namespace fs = std::filesystem;
namespace {

void RegisterCodecs() {
  static std::once_flag once;
  std::call_once(once, [] {
    DJDecoderRegistration::registerCodecs();
    DcmRLEDecoderRegistration::registerCodecs();
  });
}

// A temporary file removed when it goes out of scope.
class TempFile {
 public:
  explicit TempFile(const std::string& extension) {
    static std::atomic<int> counter{0};
    path_ = fs::temp_directory_path() /
            ("endorecon-video-" + std::to_string(::getpid()) + "-" + std::to_string(counter++) + extension);
  }
  ~TempFile() {
    std::error_code ignored;
    fs::remove(path_, ignored);
  }
  TempFile(const TempFile&) = delete;
  TempFile& operator=(const TempFile&) = delete;
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

// A file's header and what reading its pixels needs besides.
struct Instance : InstanceHeader {
  explicit Instance(InstanceHeader header) : InstanceHeader(std::move(header)) {}
  std::unique_ptr<TempFile> stream;  // a video's extracted stream
  std::vector<double> times;         // seconds from the instance's first frame
  std::string times_from;
};

// One fragment of encapsulated pixel data (item 0 is the basic offset table).
struct Fragment {
  const Uint8* data = nullptr;
  std::size_t size = 0;
};

// The encapsulated pixel data's items, the offset table first. Throws FailInvalid naming the file for
// pixel data that is not encapsulated or a fragment that cannot be read.
std::vector<Fragment> Fragments(const Instance& instance) {
  DcmPixelSequence* sequence = &EncapsulatedPixels(instance);
  std::vector<Fragment> fragments(sequence->card());
  for (unsigned long i = 0; i < sequence->card(); ++i) {
    DcmPixelItem* item = nullptr;
    Uint8* data = nullptr;
    if (sequence->getItem(item, i).bad() || item->getUint8Array(data).bad() ||
        (data == nullptr && item->getLength() > 0)) {
      FailInvalid(Where(instance) + ": truncated pixel stream: fragment " + std::to_string(i) + " of " +
                  std::to_string(sequence->card() - 1) + " cannot be read");
    }
    fragments[i] = {data, item->getLength()};
  }
  return fragments;
}

// Writes the fragments of the encapsulated pixel data (the offset table left out) to a file that
// FFmpeg opens: DICOM carries the MPEG stream in fragments, in order.
void ExtractStream(Instance& instance) {
  const std::vector<Fragment> fragments = Fragments(instance);
  const bool mpeg2 = instance.transfer_syntax == UID_MPEG2MainProfileAtMainLevelTransferSyntax ||
                     instance.transfer_syntax == UID_MPEG2MainProfileAtHighLevelTransferSyntax;
  instance.stream = std::make_unique<TempFile>(mpeg2 ? ".mpg" : ".mp4");
  std::ofstream out(instance.stream->path(), std::ios::binary);
  std::uint64_t bytes = 0;
  for (std::size_t i = 1; i < fragments.size(); ++i) {
    out.write(reinterpret_cast<const char*>(fragments[i].data),
              static_cast<std::streamsize>(fragments[i].size));
    bytes += fragments[i].size;
  }
  out.close();
  if (!out) Fail(ErrorCode::kUnavailable, "cannot write " + instance.stream->path().string());
  if (bytes == 0) FailInvalid(Where(instance) + ": the encapsulated video stream is empty");
}

// Whether a JPEG stream's header leads, by the standard's rules (ITU-T T.81 B.1.1), from its SOI
// marker through length-prefixed marker segments and fill bytes to a frame header (SOFn) whose
// length bytes and a byte after them lie in the fragment.
bool JpegHeaderReachesAFrame(const Fragment& fragment) {
  const Uint8* data = fragment.data;
  if (fragment.size < 4 || data[0] != 0xFF || data[1] != 0xD8) return false;
  const auto frame = FindJpegHeaderMarker(data, fragment.size, [](unsigned char marker) {
    return marker >= 0xC0 && marker <= 0xCF && marker != 0xC4 && marker != 0xC8 && marker != 0xCC;
  });
  return frame && *frame + 4 < fragment.size;
}

// DCMTK 3.6.7 scans each JPEG frame's header for its bit depth before decoding it, and never returns
// on some malformed headers (a TEM marker before the frame header: tests/fuzz/dicom_recording_fuzz.cc
// found it). So the first fragment of every frame is walked here first; the frames' first fragments
// are those the offset table points at, every fragment when there is one per frame, or else those
// that start with SOI, as DCMTK finds them.
void CheckJpegHeaders(const Instance& instance) {
  const std::vector<Fragment> fragments = Fragments(instance);
  const std::size_t count = fragments.size() - 1;
  std::vector<std::size_t> starts;
  if (fragments[0].size == 4 * static_cast<std::size_t>(instance.frames)) {
    std::map<std::uint64_t, std::size_t> item_at;  // byte offset after the offset table -> item
    std::uint64_t offset = 0;
    for (std::size_t i = 1; i < fragments.size(); ++i) {
      item_at[offset] = i;
      offset += 8 + fragments[i].size;
    }
    for (int f = 0; f < instance.frames; ++f) {
      const Uint8* entry = fragments[0].data + 4 * f;
      const std::uint64_t value = entry[0] | entry[1] << 8 | entry[2] << 16 | std::uint64_t(entry[3]) << 24;
      const auto found = item_at.find(value);
      if (found == item_at.end()) {
        FailInvalid(Where(instance) + ": the pixel data's offset table entry " + std::to_string(f) + " (" +
                    std::to_string(value) + ") points at no fragment");
      }
      starts.push_back(found->second);
    }
  } else if (count == static_cast<std::size_t>(instance.frames)) {
    for (std::size_t i = 1; i < fragments.size(); ++i) starts.push_back(i);
  } else {
    for (std::size_t i = 1; i < fragments.size(); ++i) {
      if (fragments[i].size >= 2 && fragments[i].data[0] == 0xFF && fragments[i].data[1] == 0xD8)
        starts.push_back(i);
    }
    if (starts.size() != static_cast<std::size_t>(instance.frames)) {
      FailInvalid(Where(instance) + ": Number of Frames is " + std::to_string(instance.frames) +
                  " but the pixel data holds " + std::to_string(starts.size()) + " JPEG streams in " +
                  std::to_string(count) + " fragments (and no offset table)");
    }
  }
  for (std::size_t f = 0; f < starts.size(); ++f) {
    if (!JpegHeaderReachesAFrame(fragments[starts[f]])) {
      FailInvalid(Where(instance) + " frame " + std::to_string(f) +
                  ": not a well-formed JPEG stream (no SOI, or its header does not lead to a frame header)");
    }
  }
}

cv::VideoCapture OpenStream(const Instance& instance) {
  cv::VideoCapture capture(instance.stream->path().string(), cv::CAP_FFMPEG);
  if (!capture.isOpened()) {
    FailInvalid(Where(instance) + ": FFmpeg cannot open the encapsulated " +
                UidName(instance.transfer_syntax) + " stream");
  }
  return capture;
}

void ReadTimes(Instance& instance) {
  DcmItem& data = *instance.dataset;
  const int n = instance.frames;
  instance.times.assign(static_cast<std::size_t>(n), 0.0);
  const auto vector = FindNumbers(data, DCM_FrameTimeVector);
  if (!vector.empty()) {
    if (static_cast<int>(vector.size()) != n) {
      FailInvalid(Where(instance) + ": Frame Time Vector (0018,1065) has " + std::to_string(vector.size()) +
                  " values for " + std::to_string(n) + " frames");
    }
    for (int i = 1; i < n; ++i) {
      if (!std::isfinite(vector[i]) || vector[i] < 0) {
        FailInvalid(Where(instance) + ": Frame Time Vector (0018,1065) value " + std::to_string(i) +
                    " is not a non-negative number of milliseconds");
      }
      instance.times[i] = instance.times[i - 1] + vector[i] / 1000.0;
    }
    instance.times_from = "Frame Time Vector (0018,1065)";
    return;
  }
  double interval = 0;
  if (const auto frame_time = FindNumber(data, DCM_FrameTime); frame_time && *frame_time > 0) {
    interval = *frame_time / 1000.0;
    instance.times_from = "Frame Time (0018,1063)";
  } else if (const auto rate = FindNumber(data, DCM_CineRate); rate && *rate > 0) {
    interval = 1.0 / *rate;
    instance.times_from = "Cine Rate (0018,0040)";
  } else if (const auto display = FindNumber(data, DCM_RecommendedDisplayFrameRate);
             display && *display > 0) {
    interval = 1.0 / *display;
    instance.times_from = "Recommended Display Frame Rate (0008,2144)";
  } else if (instance.video) {
    const double fps = OpenStream(instance).get(cv::CAP_PROP_FPS);
    if (fps > 0 && std::isfinite(fps)) {
      interval = 1.0 / fps;
      instance.times_from = "the video stream's frame rate";
    }
  }
  if (interval <= 0) {
    interval = 1.0;
    instance.times_from = "none in the file (frames taken one second apart)";
  }
  for (int i = 0; i < n; ++i) instance.times[i] = i * interval;
}

// What decoding the file's frames needs besides its header: the video stream extracted, JPEG
// headers checked, every fragment of encapsulated pixel data readable, the frames' times.
Instance LoadInstance(InstanceHeader header) {
  RegisterCodecs();
  Instance instance(std::move(header));
  if (instance.video) {
    ExtractStream(instance);
  } else if (DcmXfer(instance.xfer).isEncapsulated()) {
    Fragments(instance);  // a truncated fragment named here, not by the decoder's words
  }
  if (instance.xfer == EXS_JPEGProcess1 || instance.xfer == EXS_JPEGProcess2_4 ||
      instance.xfer == EXS_JPEGProcess14 || instance.xfer == EXS_JPEGProcess14SV1) {
    CheckJpegHeaders(instance);
  }
  ReadTimes(instance);
  return instance;
}

cv::Mat ToBgr(const void* data, int rows, int columns, bool monochrome) {
  cv::Mat bgr;
  if (monochrome) {
    cv::cvtColor(cv::Mat(rows, columns, CV_8UC1, const_cast<void*>(data)), bgr, cv::COLOR_GRAY2BGR);
  } else {
    cv::cvtColor(cv::Mat(rows, columns, CV_8UC3, const_cast<void*>(data)), bgr, cv::COLOR_RGB2BGR);
  }
  return bgr;
}

cv::Mat DecodeImageFrame(const Instance& instance, int frame) {
  DicomImage image(instance.dataset, instance.xfer, CIF_UsePartialAccessToPixelData,
                   static_cast<unsigned long>(frame), 1);
  const std::string where = Where(instance) + " frame " + std::to_string(frame);
  if (image.getStatus() != EIS_Normal) {
    FailInvalid(where + ": cannot decode the pixel data (" + DicomImage::getString(image.getStatus()) +
                "); a truncated pixel stream?");
  }
  if (image.isMonochrome()) image.setMinMaxWindow();
  const void* data = image.getOutputData(8, 0, 0);
  if (data == nullptr) FailInvalid(where + ": cannot decode the pixel data; a truncated pixel stream?");
  return ToBgr(data, instance.rows, instance.columns, image.isMonochrome() != 0);
}

// One frame of the recording: which instance and which of its frames, and when.
struct FrameRef {
  std::size_t index = 0;  // in the series' timeline
  std::size_t instance = 0;
  int frame = 0;
  double time = 0;
};

std::vector<FrameRef> Timeline(const std::vector<Instance>& series) {
  std::vector<FrameRef> frames;
  double offset = 0;
  for (std::size_t i = 0; i < series.size(); ++i) {
    const auto& times = series[i].times;
    for (int f = 0; f < series[i].frames; ++f) frames.push_back({frames.size(), i, f, offset + times[f]});
    const double step = times.size() > 1 ? (times.back() - times.front()) / (times.size() - 1) : 1.0;
    offset += times.back() + step;
  }
  return frames;
}

std::vector<FrameRef> Select(const std::vector<FrameRef>& all, const RecordingOptions& options,
                             const std::string& where) {
  const int n = static_cast<int>(all.size());
  const FrameRange& w = options.frames;
  CheckWindowHoldsFrames(w, n, where);  // then the first frame is picked, whatever the fps
  std::vector<FrameRef> picked;
  double next_time = -INFINITY;
  for (const int i : w.Of(n)) {
    if (options.fps > 0) {
      if (all[i].time + 1e-9 < next_time) continue;
      next_time = (picked.empty() ? all[i].time : next_time) + 1.0 / options.fps;
    }
    picked.push_back(all[i]);
  }
  return picked;
}

// Decodes the picked frames of one series (in timeline order).
std::vector<cv::Mat> Decode(const std::vector<Instance>& series, const std::vector<FrameRef>& picked) {
  std::vector<cv::Mat> frames(picked.size());
  for (std::size_t i = 0; i < series.size(); ++i) {
    const Instance& instance = series[i];
    std::map<int, std::vector<std::size_t>> wanted;  // instance frame -> output slots
    for (std::size_t k = 0; k < picked.size(); ++k) {
      if (picked[k].instance == i) wanted[picked[k].frame].push_back(k);
    }
    if (!instance.video) {
      for (const auto& [frame, slots] : wanted) {
        const cv::Mat image = DecodeImageFrame(instance, frame);
        for (const auto slot : slots) frames[slot] = image;
      }
      continue;
    }
    // Every frame is decoded, so a stream shorter than Number of Frames is found even when the
    // window ends early.
    cv::VideoCapture capture = OpenStream(instance);
    cv::Mat image;
    int decoded = 0;
    while (decoded < instance.frames && capture.read(image)) {
      if (image.rows != instance.rows || image.cols != instance.columns) {
        FailInvalid(Where(instance) + " frame " + std::to_string(decoded) + ": the stream's frames are " +
                    std::to_string(image.cols) + "x" + std::to_string(image.rows) +
                    " but Rows x Columns say " + std::to_string(instance.columns) + "x" +
                    std::to_string(instance.rows));
      }
      if (const auto found = wanted.find(decoded); found != wanted.end()) {
        for (const auto slot : found->second) frames[slot] = image.clone();
      }
      ++decoded;
    }
    if (decoded < instance.frames) {
      FailInvalid(Where(instance) + ": truncated or damaged pixel stream: Number of Frames is " +
                  std::to_string(instance.frames) + " but the stream decodes to " + std::to_string(decoded) +
                  " frame(s)");
    }
    if (capture.read(image)) {
      spdlog::warn(
          "{}: the pixel stream holds more frames than Number of Frames (0028,0008) declares ({}); "
          "only those are read",
          Where(instance), instance.frames);
    }
  }
  return frames;
}

std::vector<cv::Mat> Split(std::vector<cv::Mat>& frames, StereoLayout layout, const std::string& where) {
  std::vector<cv::Mat> right;
  for (auto& frame : frames) {
    const FrameSize eye = EyeSize(layout, frame.cols, frame.rows, where);
    const cv::Rect second = layout == StereoLayout::kSideBySide
                                ? cv::Rect(eye.width, 0, eye.width, eye.height)
                                : cv::Rect(0, eye.height, eye.width, eye.height);
    right.push_back(frame(second).clone());
    frame = frame(cv::Rect(0, 0, eye.width, eye.height)).clone();
  }
  return right;
}

// The recording's series (recording_series.h), checked against `stereo`, each file's pixels then
// made ready to decode.
std::vector<std::vector<Instance>> LoadSeries(const fs::path& path, StereoLayout stereo) {
  auto all = LoadSeriesHeaders(path);
  CheckSeriesFitLayout(all, stereo, path);
  std::vector<std::vector<Instance>> series;
  for (auto& headers : all) {
    auto& instances = series.emplace_back();
    for (auto& header : headers) instances.push_back(LoadInstance(std::move(header)));
  }
  return series;
}

std::string Describe(const std::vector<Instance>& series) {
  const Instance& first = series.front();
  int frames = 0;
  for (const auto& instance : series) frames += instance.frames;
  return UidName(first.sop_class) + ", " + UidName(first.transfer_syntax) + ", " +
         std::to_string(series.size()) + " instance(s), " + std::to_string(frames) + " frame(s) of " +
         std::to_string(first.columns) + "x" + std::to_string(first.rows);
}

}  // namespace

Recording ReadRecording(const fs::path& path, const RecordingOptions& options) {
  const auto series = LoadSeries(path, options.stereo);
  const bool two = options.stereo == StereoLayout::kTwoSeries;
  Recording recording;
  const auto timeline = Timeline(series[0]);
  recording.recording_frames = static_cast<int>(timeline.size());
  const auto picked = Select(timeline, options, path.string());
  recording.left = Decode(series[0], picked);
  if (two) {
    const auto right_timeline = Timeline(series[1]);  // as many frames: CheckSeriesFitLayout
    std::vector<FrameRef> right_picked;
    for (const auto& ref : picked) right_picked.push_back(right_timeline[ref.index]);
    recording.right = Decode(series[1], right_picked);
    if (recording.right.front().size() != recording.left.front().size()) {
      FailInvalid(path.string() + ": the right series' frames differ in size from the left's");
    }
  } else if (options.stereo != StereoLayout::kMono) {
    recording.right = Split(recording.left, options.stereo, path.string());
  }
  for (const auto& ref : picked) {
    recording.times_s.push_back(ref.time - picked.front().time);
    recording.frame_numbers.push_back(static_cast<int>(ref.index));
  }
  recording.times_from = series[0].front().times_from;
  // A series of one-frame instances has no time between them: the timeline takes them a second
  // apart, which recording.json credited to the first instance's Frame Time Vector (found 2026-12-07).
  const bool single_frames = std::all_of(series[0].begin(), series[0].end(),
                                         [](const Instance& instance) { return instance.frames == 1; });
  if (series[0].size() > 1 && single_frames)
    recording.times_from = "none between its instances (one frame each, taken one second apart)";
  recording.study = ReadStudyContext(*series[0].front().dataset, series[0].front().path.string());
  for (std::size_t i = 1; i < series[0].size(); ++i) {
    recording.study.source_instances.push_back(
        {series[0][i].sop_class, FindString(*series[0][i].dataset, DCM_SOPInstanceUID).value_or("")});
  }
  recording.description = Describe(series[0]) + (two ? " (and a right series)" : "");
  return recording;
}

}  // namespace endorecon::dicom
