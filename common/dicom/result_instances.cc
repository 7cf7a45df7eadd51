#include "endorecon_version.h"
#include "common/dicom/result_instances.h"

#include <dcmtk/dcmdata/dctk.h>

#include <cmath>
#include <cstdio>

#include "common/dicom/dataset_access.h"
#include "common/dicom/file_save.h"
#include "common/dicom/rgb_pixels.h"
#include "common/dicom/uid.h"
#include "common/error.h"

namespace endorecon::dicom {
namespace {

constexpr const char* kManufacturer = "endorecon";

DcmItem* AppendItem(DcmItem& parent, const DcmTagKey& sequence) {
  DcmItem* item = nullptr;
  if (parent.findOrCreateSequenceItem(sequence, item, -2).bad() || item == nullptr) {
    Fail(ErrorCode::kInternal, "cannot add an item to " + TagName(sequence));
  }
  return item;
}

void PutReference(DcmItem& item, const SourceInstance& source) {
  Put(item, DCM_ReferencedSOPClassUID, source.sop_class_uid);
  Put(item, DCM_ReferencedSOPInstanceUID, source.sop_instance_uid);
}

// The parts every result instance shares: SOP Common, patient and study, the new series, the
// equipment, the derivation and the references to the source series. Returns the SOP Instance UID.
std::string PutCommon(DcmDataset& data, const SeriesHeader& header, const std::string& sop_class,
                      const std::string& modality) {
  WriteStudyModules(header.study, data);
  const std::string sop_uid = NewUid(header.uid_root);
  OFString date, time;
  DcmDate::getCurrentDate(date);
  DcmTime::getCurrentTime(time);
  Put(data, DCM_SOPClassUID, sop_class);
  Put(data, DCM_SOPInstanceUID, sop_uid);
  Put(data, DCM_InstanceCreationDate, date.c_str());
  Put(data, DCM_InstanceCreationTime, time.c_str());
  Put(data, DCM_Modality, modality);
  Put(data, DCM_Laterality, "");  // Type 2C: the body part may be paired; unknown here
  Put(data, DCM_SeriesInstanceUID, NewUid(header.uid_root));
  Put(data, DCM_SeriesNumber, std::to_string(header.series_number));
  Put(data, DCM_SeriesDescription, header.series_description);
  Put(data, DCM_SeriesDate, date.c_str());
  Put(data, DCM_SeriesTime, time.c_str());
  Put(data, DCM_InstanceNumber, "1");
  Put(data, DCM_ContentDate, date.c_str());
  Put(data, DCM_ContentTime, time.c_str());
  Put(data, DCM_Manufacturer, kManufacturer);
  Put(data, DCM_SoftwareVersions, ENDORECON_VERSION);
  Put(data, DCM_DerivationDescription, header.derivation_description.substr(0, 1024));
  if (!header.study.source_series_uid.empty()) {
    DcmItem* series = AppendItem(data, DCM_ReferencedSeriesSequence);
    Put(*series, DCM_SeriesInstanceUID, header.study.source_series_uid);
    for (const auto& source : header.study.source_instances) {
      PutReference(*AppendItem(*series, DCM_ReferencedInstanceSequence), source);
    }
  }
  return sop_uid;
}

// The image parts: General Image, SC Equipment, Multi-frame and Cine with the frames' times.
void PutImage(DcmDataset& data, const SeriesHeader& header, int frames, int width, int height) {
  Put(data, DCM_ImageType, "DERIVED\\SECONDARY");
  Put(data, DCM_ConversionType, "SYN");
  Put(data, DCM_PatientOrientation, "");
  Put(data, DCM_BurnedInAnnotation, "NO");
  Put(data, DCM_NumberOfFrames, std::to_string(frames));
  PutUint16(data, DCM_Rows, static_cast<Uint16>(height));
  PutUint16(data, DCM_Columns, static_cast<Uint16>(width));
  PutUint16(data, DCM_PixelRepresentation, 0);
  for (const auto& source : header.study.source_instances) {
    PutReference(*AppendItem(data, DCM_SourceImageSequence), source);
  }
  if (frames == 1) return;  // Frame Increment Pointer and the times are for more than one frame
  if (header.frame_times_s.empty()) {
    Put(data, DCM_FrameTime, DecimalString(1000.0 / 15.0));
    PutTag(data, DCM_FrameIncrementPointer, DCM_FrameTime);
    return;
  }
  if (static_cast<int>(header.frame_times_s.size()) != frames) {
    FailInvalid("frame times: " + std::to_string(header.frame_times_s.size()) + " for " +
                std::to_string(frames) + " frames");
  }
  Put(data, DCM_FrameTimeVector, FrameTimeVector(header.frame_times_s));
  PutTag(data, DCM_FrameIncrementPointer, DCM_FrameTimeVector);
}

// Sets Pixel Data (8- or 16-bit samples) and writes the file.
template <typename Sample>
void SaveWithPixels(DcmFileFormat& file, const std::filesystem::path& path,
                    const std::vector<Sample>& pixels) {
  DcmDataset& data = *file.getDataset();
  const auto count = static_cast<unsigned long>(pixels.size());
  OFCondition status;
  if constexpr (sizeof(Sample) == 1) {
    status = data.putAndInsertUint8Array(DCM_PixelData, pixels.data(), count);
  } else {
    status = data.putAndInsertUint16Array(DCM_PixelData, pixels.data(), count);
  }
  if (status.bad()) Fail(ErrorCode::kInternal, "cannot set Pixel Data of " + path.string());
  SaveFile(file, path, EXS_LittleEndianExplicit);
}

void CheckSize(int width, int height, const std::filesystem::path& path) {
  if (width <= 0 || height <= 0 || width > 65535 || height > 65535) {
    FailInvalid(path.string() + ": frames of " + std::to_string(width) + "x" + std::to_string(height) +
                " do not fit a DICOM image");
  }
}

}  // namespace

std::string WriteColorFrames(const std::filesystem::path& path, const SeriesHeader& header,
                             const std::vector<cv::Mat>& frames) {
  if (frames.empty()) FailInvalid(path.string() + ": no frames to write");
  const int width = frames[0].cols, height = frames[0].rows;
  CheckSize(width, height, path);
  DcmFileFormat file;
  DcmDataset& data = *file.getDataset();
  const std::string uid = PutCommon(data, header, UID_MultiframeTrueColorSecondaryCaptureImageStorage, "ES");
  PutImage(data, header, static_cast<int>(frames.size()), width, height);
  PutUint16(data, DCM_SamplesPerPixel, 3);
  Put(data, DCM_PhotometricInterpretation, "RGB");
  PutUint16(data, DCM_PlanarConfiguration, 0);
  PutUint16(data, DCM_BitsAllocated, 8);
  PutUint16(data, DCM_BitsStored, 8);
  PutUint16(data, DCM_HighBit, 7);
  SaveWithPixels(file, path, InterleavedRgb(frames, path.string()));
  return uid;
}

std::string WriteScalarFrames(const std::filesystem::path& path, const SeriesHeader& header,
                              const std::vector<std::vector<float>>& frames, int width, int height,
                              const ScalarUnits& units) {
  if (frames.empty()) FailInvalid(path.string() + ": no frames to write");
  CheckSize(width, height, path);
  const std::size_t pixels_per_frame = static_cast<std::size_t>(width) * height;
  double largest = 0;
  for (std::size_t f = 0; f < frames.size(); ++f) {
    if (frames[f].size() != pixels_per_frame) {
      FailInvalid(path.string() + ": frame " + std::to_string(f) + " has " +
                  std::to_string(frames[f].size()) + " values for " + std::to_string(width) + "x" +
                  std::to_string(height));
    }
    for (const float v : frames[f]) {
      if (std::isfinite(v)) largest = std::max(largest, static_cast<double>(v));
    }
  }
  // The slope is a DS of at most 16 characters: round it up so the largest value still fits.
  const double slope = std::stod(DecimalString(largest > 0 ? largest / 65535.0 * (1 + 1e-6) : 1.0));
  DcmFileFormat file;
  DcmDataset& data = *file.getDataset();
  const std::string uid =
      PutCommon(data, header, UID_MultiframeGrayscaleWordSecondaryCaptureImageStorage, "ES");
  PutImage(data, header, static_cast<int>(frames.size()), width, height);
  PutUint16(data, DCM_SamplesPerPixel, 1);
  Put(data, DCM_PhotometricInterpretation, "MONOCHROME2");
  PutUint16(data, DCM_BitsAllocated, 16);
  PutUint16(data, DCM_BitsStored, 16);
  PutUint16(data, DCM_HighBit, 15);
  Put(data, DCM_RescaleIntercept, "0");
  Put(data, DCM_RescaleSlope, DecimalString(slope));
  Put(data, DCM_RescaleType, units.rescale_type);
  Put(data, DCM_PresentationLUTShape, "IDENTITY");
  Put(data, DCM_WindowCenter, DecimalString(largest / 2));
  Put(data, DCM_WindowWidth, DecimalString(std::max(largest, slope)));
  Put(data, DCM_ImageComments, units.description.substr(0, 10240));
  std::vector<Uint16> stored(pixels_per_frame * frames.size());
  for (std::size_t f = 0; f < frames.size(); ++f) {
    for (std::size_t i = 0; i < pixels_per_frame; ++i) {
      const float v = frames[f][i];
      const double q = std::isfinite(v) && v > 0 ? std::round(v / slope) : 0.0;
      stored[f * pixels_per_frame + i] = static_cast<Uint16>(std::min(q, 65535.0));
    }
  }
  SaveWithPixels(file, path, stored);
  return uid;
}

std::string WriteStlMesh(const std::filesystem::path& path, const SeriesHeader& header,
                         const std::string& stl, const std::string& unit) {
  if (stl.size() < 84) FailInvalid(path.string() + ": the STL file is shorter than its 84-byte header");
  DcmFileFormat file;
  DcmDataset& data = *file.getDataset();
  const std::string uid = PutCommon(data, header, UID_EncapsulatedSTLStorage, "M3D");
  Put(data, DCM_FrameOfReferenceUID, header.frame_of_reference_uid);
  Put(data, DCM_PositionReferenceIndicator, "");
  Put(data, DCM_ManufacturerModelName, "endorecon");
  Put(data, DCM_DeviceSerialNumber, "endorecon");
  Put(data, DCM_AcquisitionDateTime, "");
  Put(data, DCM_BurnedInAnnotation, "NO");
  Put(data, DCM_DocumentTitle, header.series_description);
  PutEmpty(data, DCM_ConceptNameCodeSequence);
  Put(data, DCM_MIMETypeOfEncapsulatedDocument, "model/stl");
  for (const auto& source : header.study.source_instances) {
    PutReference(*AppendItem(data, DCM_SourceInstanceSequence), source);
  }
  DcmItem* units = AppendItem(data, DCM_MeasurementUnitsCodeSequence);
  Put(*units, DCM_CodeValue, unit);
  Put(*units, DCM_CodingSchemeDesignator, "UCUM");
  Put(*units, DCM_CodeMeaning, unit == "mm" ? "millimeter" : unit);
  std::string bytes = stl;
  if (bytes.size() % 2 != 0) bytes.push_back('\0');
  if (data.putAndInsertUint8Array(DCM_EncapsulatedDocument, reinterpret_cast<const Uint8*>(bytes.data()),
                                  static_cast<unsigned long>(bytes.size()))
          .bad()) {
    Fail(ErrorCode::kInternal, "cannot set Encapsulated Document of " + path.string());
  }
  if (data.putAndInsertUint32(DCM_EncapsulatedDocumentLength, static_cast<Uint32>(stl.size())).bad()) {
    Fail(ErrorCode::kInternal, "cannot set Encapsulated Document Length of " + path.string());
  }
  SaveFile(file, path, EXS_LittleEndianExplicit);
  return uid;
}

}  // namespace endorecon::dicom
