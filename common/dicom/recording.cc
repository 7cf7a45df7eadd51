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
#include <set>

#include "common/dicom/dataset_access.h"
#include "common/dicom_file.h"
#include "common/error.h"
#include "common/jpeg_header.h"

namespace endorecon::dicom {
namespace fs = std::filesystem;
namespace {

const std::set<std::string> kVideoClasses = {
    UID_VideoEndoscopicImageStorage, UID_VideoPhotographicImageStorage, UID_VideoMicroscopicImageStorage};
const std::set<std::string> kImageClasses = {UID_VLEndoscopicImageStorage, UID_VLPhotographicImageStorage,
                                             UID_SecondaryCaptureImageStorage,
                                             UID_MultiframeTrueColorSecondaryCaptureImageStorage,
                                             UID_MultiframeGrayscaleByteSecondaryCaptureImageStorage};
const std::set<std::string> kVideoSyntaxes = {UID_MPEG2MainProfileAtMainLevelTransferSyntax,
                                              UID_MPEG2MainProfileAtHighLevelTransferSyntax,
                                              UID_MPEG4HighProfileLevel4_1TransferSyntax,
                                              UID_MPEG4BDcompatibleHighProfileLevel4_1TransferSyntax,
                                              UID_MPEG4HighProfileLevel4_2_For2DVideoTransferSyntax,
                                              UID_MPEG4HighProfileLevel4_2_For3DVideoTransferSyntax,
                                              UID_MPEG4StereoHighProfileLevel4_2TransferSyntax,
                                              UID_HEVCMainProfileLevel5_1TransferSyntax,
                                              UID_HEVCMain10ProfileLevel5_1TransferSyntax};
const std::set<E_TransferSyntax> kImageSyntaxes = {EXS_LittleEndianImplicit, EXS_LittleEndianExplicit,
                                                   EXS_BigEndianExplicit,    EXS_DeflatedLittleEndianExplicit,
                                                   EXS_RLELossless,          EXS_JPEGProcess1,
                                                   EXS_JPEGProcess2_4,       EXS_JPEGProcess14,
                                                   EXS_JPEGProcess14SV1};

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

struct Instance {
  fs::path path;
  std::unique_ptr<DcmFileFormat> file;
  DcmDataset* dataset = nullptr;
  std::string sop_class, series_uid, transfer_syntax;
  E_TransferSyntax xfer = EXS_Unknown;
  long series_number = 0, instance_number = 0;
  int frames = 0, rows = 0, columns = 0;
  bool video = false;
  std::unique_ptr<TempFile> stream;  // a video's extracted stream
  std::vector<double> times;         // seconds from the instance's first frame
  std::string times_from;
};

std::string Where(const Instance& instance) { return instance.path.string(); }

// One fragment of encapsulated pixel data (item 0 is the basic offset table).
struct Fragment {
  const Uint8* data = nullptr;
  std::size_t size = 0;
};

// The encapsulated pixel data's items, the offset table first. Throws FailInvalid naming the file for
// pixel data that is not encapsulated or a fragment that cannot be read.
std::vector<Fragment> Fragments(const Instance& instance) {
  DcmElement* element = nullptr;
  if (instance.dataset->findAndGetElement(DCM_PixelData, element).bad() || element == nullptr) {
    FailInvalid(Where(instance) + ": no Pixel Data (7FE0,0010)");
  }
  auto* pixels = static_cast<DcmPixelData*>(element);
  DcmPixelSequence* sequence = nullptr;
  const OFCondition status = pixels->getEncapsulatedRepresentation(instance.xfer, nullptr, sequence);
  if (status.bad() || sequence == nullptr || sequence->card() == 0) {
    FailInvalid(Where(instance) + ": the pixel data is not encapsulated as " +
                UidName(instance.transfer_syntax) + " says (" + status.text() + ")");
  }
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

// The bytes of the pixel data: the fragments' for encapsulated data (the offset table left out),
// the element's length otherwise.
std::size_t PixelDataBytes(const Instance& instance) {
  if (DcmXfer(instance.xfer).isEncapsulated()) {
    const std::vector<Fragment> fragments = Fragments(instance);
    std::size_t bytes = 0;
    for (std::size_t i = 1; i < fragments.size(); ++i) bytes += fragments[i].size;
    return bytes;
  }
  DcmElement* element = nullptr;
  if (instance.dataset->findAndGetElement(DCM_PixelData, element).bad() || element == nullptr) {
    FailInvalid(Where(instance) + ": no Pixel Data (7FE0,0010)");
  }
  // Fragments of a compressed stream under a native transfer syntax (a file whose syntax was
  // rewritten): said as such, not as "0 bytes".
  if (element->getLengthField() == DCM_UndefinedLength) {
    FailInvalid(Where(instance) +
                ": the pixel data is encapsulated (compressed fragments) but the transfer "
                "syntax " +
                std::string(DcmXfer(instance.xfer).getXferName()) + " says native pixels");
  }
  return element->getLength();
}

// Number of Frames (0028,0008), 1 when absent: a whole number from 1 up to what the pixel data can
// hold at one byte a frame, checked before anything is sized by it (tests/fuzz/dicom_recording_fuzz:
// a 1 KB file declaring ten million frames cost seconds of per-frame bookkeeping).
int DeclaredFrames(const Instance& instance) {
  DcmItem& data = *instance.dataset;
  const std::optional<double> declared = FindNumber(data, DCM_NumberOfFrames);
  const double frames = declared.value_or(1);
  const std::string where = Where(instance);
  const std::string text = FindString(data, DCM_NumberOfFrames).value_or("");
  if (!(frames == std::floor(frames)) || frames > 2147483647.0 ||
      (!declared && text.find_first_not_of(' ') != std::string::npos)) {  // present, but no number
    FailInvalid(where + ": Number of Frames (0028,0008) is not a whole number of frames (\"" + text + "\")");
  }
  if (frames <= 0) FailInvalid(where + ": zero frames (Number of Frames is " + std::to_string(long(frames)) + ")");
  const std::size_t bytes = PixelDataBytes(instance);
  if (frames > double(bytes)) {
    FailInvalid(where + ": Number of Frames is " + std::to_string(long(frames)) + " but the pixel data holds " +
                std::to_string(bytes) + " bytes");
  }
  return static_cast<int>(frames);
}

Instance LoadInstance(const fs::path& path) {
  RegisterCodecs();
  Instance instance;
  instance.path = path;
  if (!IsDicomFile(path)) FailInvalid(path.string() + ": not a DICOM file (no \"DICM\" at byte 128)");
  instance.file = std::make_unique<DcmFileFormat>();
  const OFCondition loaded = instance.file->loadFile(path.c_str());
  if (loaded.bad()) FailInvalid(path.string() + ": not a readable DICOM file: " + loaded.text());
  instance.dataset = instance.file->getDataset();
  DcmItem& data = *instance.dataset;
  instance.sop_class = FindString(data, DCM_SOPClassUID).value_or("");
  if (!kVideoClasses.count(instance.sop_class) && !kImageClasses.count(instance.sop_class)) {
    FailInvalid(path.string() + ": SOP class " +
                (instance.sop_class.empty() ? std::string("(none)") : UidName(instance.sop_class)) +
                " is not a recording endorecon reads; it reads Video Endoscopic, Video Photographic, VL "
                "Endoscopic, VL Photographic and (Multi-frame) Secondary Capture images");
  }
  instance.transfer_syntax = FindString(*instance.file->getMetaInfo(), DCM_TransferSyntaxUID).value_or("");
  instance.xfer = DcmXfer(instance.transfer_syntax.c_str()).getXfer();
  if (instance.xfer == EXS_Unknown) {
    FailInvalid(path.string() + ": unknown transfer syntax '" + instance.transfer_syntax + "'");
  }
  instance.video = kVideoSyntaxes.count(instance.transfer_syntax) > 0;
  if (!instance.video && !kImageSyntaxes.count(instance.xfer)) {
    FailInvalid(path.string() + ": transfer syntax " + UidName(instance.transfer_syntax) +
                " is not one endorecon decodes (MPEG-2, MPEG-4 AVC/H.264, HEVC, uncompressed, RLE, JPEG "
                "baseline, extended or lossless)");
  }
  instance.series_uid = FindString(data, DCM_SeriesInstanceUID).value_or("");
  instance.series_number = FindInteger(data, DCM_SeriesNumber).value_or(0);
  instance.instance_number = FindInteger(data, DCM_InstanceNumber).value_or(0);
  instance.rows = static_cast<int>(FindInteger(data, DCM_Rows).value_or(0));
  instance.columns = static_cast<int>(FindInteger(data, DCM_Columns).value_or(0));
  if (instance.rows <= 0 || instance.columns <= 0) {
    FailInvalid(path.string() + ": Rows and Columns must be positive (found " +
                std::to_string(instance.rows) + " x " + std::to_string(instance.columns) + ")");
  }
  instance.frames = DeclaredFrames(instance);
  if (instance.video) ExtractStream(instance);
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
  std::vector<FrameRef> picked;
  double next_time = -INFINITY;
  for (const int i : w.Of(n)) {
    if (options.fps > 0) {
      if (all[i].time + 1e-9 < next_time) continue;
      next_time = (picked.empty() ? all[i].time : next_time) + 1.0 / options.fps;
    }
    picked.push_back(all[i]);
  }
  if (picked.empty()) {
    FailInvalid(where + ": zero frames: the window " + w.ToString() + " holds none of the recording's " +
                std::to_string(n) + " frames");
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
    if (layout == StereoLayout::kSideBySide) {
      if (frame.cols % 2 != 0) {
        FailInvalid(where + ": a side-by-side frame must have an even width, found " +
                    std::to_string(frame.cols));
      }
      const int half = frame.cols / 2;
      right.push_back(frame(cv::Rect(half, 0, half, frame.rows)).clone());
      frame = frame(cv::Rect(0, 0, half, frame.rows)).clone();
    } else {
      if (frame.rows % 2 != 0) {
        FailInvalid(where + ": a top-bottom frame must have an even height, found " +
                    std::to_string(frame.rows));
      }
      const int half = frame.rows / 2;
      right.push_back(frame(cv::Rect(0, half, frame.cols, half)).clone());
      frame = frame(cv::Rect(0, 0, frame.cols, half)).clone();
    }
  }
  return right;
}

// The SOP class a DICOM file's meta information names (Media Storage SOP Class UID), read without
// its dataset; empty when the file has none.
std::string MetaSopClass(const fs::path& path) {
  DcmFileFormat file;
  if (file.loadFile(path.c_str(), EXS_Unknown, EGL_noChange, DCM_MaxReadLength, ERM_metaOnly).bad())
    return "";
  OFString sop;
  file.getMetaInfo()->findAndGetOFString(DCM_MediaStorageSOPClassUID, sop);
  return sop.c_str();
}

// The DICOM files of `path` grouped by series, each series' instances in Instance Number order and
// the series in Series Number order. In a folder, DICOM files of other classes (a DICOMDIR, a CT, a
// report: what a CD export or a study holds beside a recording) are skipped with a warning.
std::vector<std::vector<Instance>> LoadSeries(const fs::path& path) {
  std::vector<fs::path> files;
  if (fs::is_directory(path)) {
    std::vector<std::string> skipped;  // "ct1.dcm (CTImageStorage)"
    for (const auto& entry : fs::directory_iterator(path)) {
      if (!entry.is_regular_file()) continue;
      const bool marked = IsDicomFile(entry.path());  // opened once for its mark, once more for its class
      if (!marked && !HasDicomExtension(entry.path())) continue;
      const std::string sop = marked ? MetaSopClass(entry.path()) : "";
      if (!sop.empty() && !kVideoClasses.count(sop) && !kImageClasses.count(sop)) {
        spdlog::warn("{}: skipped, SOP class {} is not a recording", entry.path().string(), UidName(sop));
        skipped.push_back(entry.path().filename().string() + " (" + UidName(sop) + ")");
        continue;
      }
      files.push_back(entry.path());
    }
    std::sort(files.begin(), files.end());
    // What was skipped is said in the error too: a submitter sees the job's reason, not the worker's
    // log (found 2026-12-07).
    if (files.empty()) {
      std::sort(skipped.begin(), skipped.end());
      constexpr std::size_t kNamed = 3;
      std::string which;
      for (std::size_t i = 0; i < std::min(skipped.size(), kNamed); ++i)
        which += (i ? ", " : "") + skipped[i];
      if (skipped.size() > kNamed) which += fmt::format(" and {} more", skipped.size() - kNamed);
      FailInvalid(path.string() + ": no DICOM recording in the folder" +
                  (skipped.empty() ? std::string()
                                   : fmt::format(" ({} DICOM file(s) of other classes skipped: {}; "
                                                 "docs/formats.md, \"DICOM recordings\", lists the "
                                                 "classes read)",
                                                 skipped.size(), which)));
    }
  } else if (fs::exists(path)) {
    files.push_back(path);
  } else {
    Fail(ErrorCode::kNotFound, path.string() + ": does not exist");
  }
  std::map<std::string, std::vector<Instance>> by_uid;
  for (const auto& file : files) {
    Instance instance = LoadInstance(file);
    by_uid[instance.series_uid].push_back(std::move(instance));
  }
  std::vector<std::vector<Instance>> series;
  for (auto& [uid, instances] : by_uid) {
    std::stable_sort(instances.begin(), instances.end(), [](const Instance& a, const Instance& b) {
      return a.instance_number < b.instance_number;
    });
    series.push_back(std::move(instances));
  }
  std::stable_sort(series.begin(), series.end(), [](const auto& a, const auto& b) {
    return a.front().series_number < b.front().series_number;
  });
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
  auto series = LoadSeries(path);
  const bool two = options.stereo == StereoLayout::kTwoSeries;
  if (series.size() != (two ? 2u : 1u)) {
    FailInvalid(path.string() + ": holds " + std::to_string(series.size()) + " series; " +
                (two ? "stereo as two series needs exactly two (left, then right, by Series Number)"
                     : "a recording is one series (or two with --stereo series); from a PACS, name its "
                       "series with --series UID"));
  }
  // The eyes are told apart by Series Number alone: equal numbers left them in the order of their
  // UIDs, which swapped the eyes without a word (found 2026-12-05).
  if (two && series[0].front().series_number == series[1].front().series_number) {
    FailInvalid(
        path.string() + ": both series have Series Number " +
        std::to_string(series[0].front().series_number) +
        "; stereo as two series takes the lower number as the left eye (give the eyes' series "
        "different numbers where the series are made: endorecon-worker to-dicom --series-number, or the "
        "recorder's settings)");
  }
  Recording recording;
  const auto timeline = Timeline(series[0]);
  recording.recording_frames = static_cast<int>(timeline.size());
  const auto picked = Select(timeline, options, path.string());
  recording.left = Decode(series[0], picked);
  if (two) {
    const auto right_timeline = Timeline(series[1]);
    if (right_timeline.size() != timeline.size()) {
      FailInvalid(path.string() + ": the right series has " + std::to_string(right_timeline.size()) +
                  " frames, the left " + std::to_string(timeline.size()));
    }
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
  recording.study = ReadStudyContext(*series[0].front().dataset, series[0].front().path.string());
  for (std::size_t i = 1; i < series[0].size(); ++i) {
    recording.study.source_instances.push_back(
        {series[0][i].sop_class, FindString(*series[0][i].dataset, DCM_SOPInstanceUID).value_or("")});
  }
  recording.description = Describe(series[0]) + (two ? " (and a right series)" : "");
  return recording;
}

}  // namespace endorecon::dicom
