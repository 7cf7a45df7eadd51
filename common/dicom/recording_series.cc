#include "common/dicom/recording_series.h"

#include <dcmtk/dcmdata/dcpxitem.h>
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>

#include "common/dicom/dataset_access.h"
#include "common/dicom_file.h"
#include "common/error.h"

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

// The bytes of the pixel data: the fragments' for encapsulated data (the offset table left out),
// the element's length otherwise; no value is loaded.
std::size_t PixelDataBytes(const InstanceHeader& instance) {
  if (DcmXfer(instance.xfer).isEncapsulated()) {
    DcmPixelSequence& sequence = EncapsulatedPixels(instance);
    std::size_t bytes = 0;
    for (unsigned long i = 1; i < sequence.card(); ++i) {
      DcmPixelItem* item = nullptr;
      if (sequence.getItem(item, i).good()) bytes += item->getLength();
    }
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
int DeclaredFrames(const InstanceHeader& instance) {
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

}  // namespace

DcmPixelSequence& EncapsulatedPixels(const InstanceHeader& instance) {
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
  return *sequence;
}

InstanceHeader LoadInstanceHeader(const fs::path& path) {
  InstanceHeader instance;
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
  return instance;
}

std::vector<std::vector<InstanceHeader>> LoadSeriesHeaders(const fs::path& path) {
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
  std::map<std::string, std::vector<InstanceHeader>> by_uid;
  for (const auto& file : files) {
    InstanceHeader instance = LoadInstanceHeader(file);
    by_uid[instance.series_uid].push_back(std::move(instance));
  }
  std::vector<std::vector<InstanceHeader>> series;
  for (auto& [uid, instances] : by_uid) {
    std::stable_sort(instances.begin(), instances.end(), [](const InstanceHeader& a, const InstanceHeader& b) {
      return a.instance_number < b.instance_number;
    });
    series.push_back(std::move(instances));
  }
  std::stable_sort(series.begin(), series.end(), [](const auto& a, const auto& b) {
    return a.front().series_number < b.front().series_number;
  });
  return series;
}

void CheckSeriesFitLayout(const std::vector<std::vector<InstanceHeader>>& series, StereoLayout stereo,
                          const fs::path& path) {
  const bool two = stereo == StereoLayout::kTwoSeries;
  if (series.size() != (two ? 2u : 1u)) {
    FailInvalid(path.string() + ": holds " + std::to_string(series.size()) + " series; " +
                (two ? "stereo as two series needs exactly two (left, then right, by Series Number)"
                     : "a recording is one series (or two with --stereo series); from a PACS, name its "
                       "series with --series UID"));
  }
  if (!two) return;
  // The eyes are told apart by Series Number alone: equal numbers left them in the order of their
  // UIDs, which swapped the eyes without a word (found 2026-12-05).
  if (series[0].front().series_number == series[1].front().series_number) {
    FailInvalid(
        path.string() + ": both series have Series Number " +
        std::to_string(series[0].front().series_number) +
        "; stereo as two series takes the lower number as the left eye (give the eyes' series "
        "different numbers where the series are made: endorecon-worker to-dicom --series-number, or the "
        "recorder's settings)");
  }
  // Two eyes of one recording share a study (and so a patient): series of two studies paired as eyes
  // ran, the results filed in the left's study (found 2026-12-07).
  const auto study = [](const InstanceHeader& instance) {
    return FindString(*instance.dataset, DCM_StudyInstanceUID).value_or("");
  };
  if (study(series[0].front()) != study(series[1].front())) {
    FailInvalid(path.string() +
                ": the two series belong to different studies (Study Instance UID): the eyes of "
                "one recording share one (endorecon-worker to-dicom: give both eyes one "
                "--study-uid)");
  }
  if (SeriesFrames(series[1]) != SeriesFrames(series[0])) {
    FailInvalid(path.string() + ": the right series has " + std::to_string(SeriesFrames(series[1])) +
                " frames, the left " + std::to_string(SeriesFrames(series[0])));
  }
  if (series[1].front().columns != series[0].front().columns || series[1].front().rows != series[0].front().rows) {
    FailInvalid(path.string() + ": the right series' frames differ in size from the left's");
  }
}

int SeriesFrames(const std::vector<InstanceHeader>& series) {
  int frames = 0;
  for (const auto& instance : series) frames += instance.frames;
  return frames;
}

FrameSize EyeSize(StereoLayout stereo, int columns, int rows, const std::string& where) {
  if (stereo == StereoLayout::kSideBySide) {
    if (columns % 2 != 0) {
      FailInvalid(where + ": a side-by-side frame must have an even width, found " + std::to_string(columns));
    }
    return {columns / 2, rows};
  }
  if (stereo == StereoLayout::kTopBottom) {
    if (rows % 2 != 0) {
      FailInvalid(where + ": a top-bottom frame must have an even height, found " + std::to_string(rows));
    }
    return {columns, rows / 2};
  }
  return {columns, rows};
}

}  // namespace endorecon::dicom
