#include "common/dicom/recording_writer.h"

#include <dcmtk/dcmdata/dcpixseq.h>
#include <dcmtk/dcmdata/dcpxitem.h>
#include <dcmtk/dcmdata/dctk.h>
// DCMTK's JPEG encoder reads colour frames through dcmimage's colour support, which this header's
// static object registers: without it a program that never reads DICOM (fuzz_seed_maker) could not
// compress RGB ("unsupported value for 'PhotometricInterpretation' (RGB)").
#include <dcmtk/dcmimage/diregist.h>
#include <dcmtk/dcmjpeg/djencode.h>
#include <dcmtk/dcmjpeg/djrploss.h>

#include <fstream>
#include <mutex>

#include "common/dicom/dataset_access.h"
#include "common/dicom/file_save.h"
#include "common/dicom/rgb_pixels.h"
#include "common/dicom/uid.h"
#include "common/error.h"
#include "common/file_read.h"

namespace endorecon::dicom {
namespace fs = std::filesystem;
namespace {

// Patient, study, series and the endoscopic image parts both writers share.
void PutHeader(DcmDataset& data, const RecordingHeader& header, const std::string& sop_class,
               const std::string& sop_uid) {
  WriteStudyModules(header.study, data);
  OFString date, time;
  DcmDate::getCurrentDate(date);
  DcmTime::getCurrentTime(time);
  Put(data, DCM_SOPClassUID, sop_class);
  Put(data, DCM_SOPInstanceUID, sop_uid);
  Put(data, DCM_Modality, "ES");
  Put(data, DCM_SeriesInstanceUID, header.series_uid.empty() ? NewUid(header.uid_root) : header.series_uid);
  Put(data, DCM_SeriesNumber, std::to_string(header.series_number));
  Put(data, DCM_SeriesDescription, header.series_description);
  Put(data, DCM_InstanceNumber, "1");
  Put(data, DCM_ContentDate, date.c_str());
  Put(data, DCM_ContentTime, time.c_str());
  Put(data, DCM_AcquisitionDateTime, std::string(date.c_str()) + time.c_str());
  Put(data, DCM_Manufacturer, "endorecon");
  Put(data, DCM_PatientOrientation, "");
  Put(data, DCM_ImageType, "ORIGINAL\\PRIMARY");
  Put(data, DCM_LossyImageCompression, "00");
  // Type 2C Laterality and Type 2 Acquisition Context present and empty (unknown); Anatomic Region
  // (Type 1C, "if known") left out: present, it must hold a coded region (dciodvfy).
  Put(data, DCM_Laterality, "");
  PutEmpty(data, DCM_AcquisitionContextSequence);
  Put(data, DCM_BurnedInAnnotation, "NO");
  PutUint16(data, DCM_SamplesPerPixel, 3);
  PutUint16(data, DCM_BitsAllocated, 8);
  PutUint16(data, DCM_BitsStored, 8);
  PutUint16(data, DCM_HighBit, 7);
  PutUint16(data, DCM_PixelRepresentation, 0);
  PutUint16(data, DCM_PlanarConfiguration, 0);
}

}  // namespace

std::string WriteVideoEndoscopic(const fs::path& video, int frames, int width, int height, double fps,
                                 const RecordingHeader& header, const fs::path& out) {
  RequireRegularFile(video);
  std::ifstream in(video, std::ios::binary);
  if (!in) FailInvalid(video.string() + ": cannot read the video");
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (bytes.empty()) FailInvalid(video.string() + ": the video is empty");
  if (frames <= 0 || width <= 0 || height <= 0 || !(fps > 0)) {
    FailInvalid(video.string() + ": frames, size and frame rate must be positive");
  }
  if (bytes.size() % 2 != 0) bytes.push_back('\0');  // fragments have an even length
  DcmFileFormat file;
  DcmDataset& data = *file.getDataset();
  const std::string uid = NewUid(header.uid_root);
  PutHeader(data, header, UID_VideoEndoscopicImageStorage, uid);
  Put(data, DCM_LossyImageCompression, "01");
  Put(data, DCM_LossyImageCompressionMethod, "ISO_14496_10");
  Put(data, DCM_PhotometricInterpretation, "YBR_PARTIAL_420");
  PutUint16(data, DCM_Rows, static_cast<Uint16>(height));
  PutUint16(data, DCM_Columns, static_cast<Uint16>(width));
  Put(data, DCM_NumberOfFrames, std::to_string(frames));
  PutTag(data, DCM_FrameIncrementPointer, DCM_FrameTime);
  Put(data, DCM_FrameTime, DecimalString(1000.0 / fps));
  Put(data, DCM_CineRate, std::to_string(static_cast<int>(std::lround(fps))));
  Put(data, DCM_RecommendedDisplayFrameRate, std::to_string(static_cast<int>(std::lround(fps))));
  Put(data, DCM_StartTrim, "1");
  Put(data, DCM_StopTrim, std::to_string(frames));
  auto* pixels = new DcmPixelData(DCM_PixelData);
  auto* sequence = new DcmPixelSequence(DCM_PixelSequenceTag);
  sequence->insert(new DcmPixelItem(DCM_PixelItemTag));  // the empty offset table
  auto* fragment = new DcmPixelItem(DCM_PixelItemTag);
  fragment->putUint8Array(reinterpret_cast<const Uint8*>(bytes.data()), static_cast<Uint32>(bytes.size()));
  sequence->insert(fragment);
  pixels->putOriginalRepresentation(EXS_MPEG4HighProfileLevel4_1, nullptr, sequence);
  data.insert(pixels, true);
  SaveFile(file, out, EXS_MPEG4HighProfileLevel4_1);
  return uid;
}

std::string WriteEndoscopicFrames(const std::vector<cv::Mat>& frames, const std::vector<double>& times_s,
                                  bool jpeg, const RecordingHeader& header, const fs::path& out) {
  if (frames.empty()) FailInvalid(out.string() + ": no frames to write");
  if (times_s.size() != frames.size()) FailInvalid(out.string() + ": one time per frame is needed");
  const int width = frames[0].cols, height = frames[0].rows;
  DcmFileFormat file;
  DcmDataset& data = *file.getDataset();
  const std::string uid = NewUid(header.uid_root);
  PutHeader(data, header, UID_VLEndoscopicImageStorage, uid);
  Put(data, DCM_PhotometricInterpretation, "RGB");
  PutUint16(data, DCM_Rows, static_cast<Uint16>(height));
  PutUint16(data, DCM_Columns, static_cast<Uint16>(width));
  Put(data, DCM_NumberOfFrames, std::to_string(frames.size()));
  PutTag(data, DCM_FrameIncrementPointer, DCM_FrameTimeVector);
  Put(data, DCM_FrameTimeVector, FrameTimeVector(times_s));
  const std::vector<Uint8> rgb = InterleavedRgb(frames, out.string());
  data.putAndInsertUint8Array(DCM_PixelData, rgb.data(), static_cast<unsigned long>(rgb.size()));
  if (!jpeg) {
    SaveFile(file, out, EXS_LittleEndianExplicit);
    return uid;
  }
  static std::once_flag once;
  // The SOP Instance UID stays the one made under the caller's root: by default the codec made a new
  // one under DCMTK's root and referenced a predecessor that exists nowhere (found 2026-12-07).
  std::call_once(once, [] { DJEncoderRegistration::registerCodecs(ECC_lossyYCbCr, EUC_never); });
  DJ_RPLossy quality(90);
  if (data.chooseRepresentation(EXS_JPEGProcess1, &quality).bad() || !data.canWriteXfer(EXS_JPEGProcess1)) {
    Fail(ErrorCode::kInternal, out.string() + ": DCMTK could not JPEG-compress the frames");
  }
  Put(data, DCM_LossyImageCompression, "01");
  Put(data, DCM_LossyImageCompressionMethod, "ISO_10918_1");
  SaveFile(file, out, EXS_JPEGProcess1);
  return uid;
}

}  // namespace endorecon::dicom
