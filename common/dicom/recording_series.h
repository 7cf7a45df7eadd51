// A DICOM recording's files read for their headers alone: which classes and transfer syntaxes, how
// many frames of what size, in which series and order. No pixel is decoded and no pixel data is
// loaded (DCMTK reads large values only when asked), so the server checks a job's recording options
// against an uploaded recording in milliseconds (recording_header.h) and the worker reads its frames
// from the same headers (recording.h). Internal to common/dicom.
#pragma once

#include <dcmtk/dcmdata/dcpixseq.h>
#include <dcmtk/dcmdata/dctk.h>

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "common/dicom/recording_layout.h"
#include "common/prepare_flags.h"

namespace endorecon::dicom {

struct InstanceHeader {
  std::filesystem::path path;
  std::unique_ptr<DcmFileFormat> file;
  DcmDataset* dataset = nullptr;
  std::string sop_class, series_uid, transfer_syntax;
  E_TransferSyntax xfer = EXS_Unknown;
  long series_number = 0, instance_number = 0;
  int frames = 0, rows = 0, columns = 0;
  bool video = false;  // an MPEG-2, H.264 or HEVC stream; else images DCMTK decodes
};

// The file as messages name it.
inline std::string Where(const InstanceHeader& instance) { return instance.path.string(); }

// The encapsulated pixel data's items (the offset table first), their values not loaded. Throws
// FailInvalid naming the file when there is no pixel data or it is not encapsulated.
DcmPixelSequence& EncapsulatedPixels(const InstanceHeader& instance);

// Loads one file's header. Throws FailInvalid naming the file for: not DICOM, not readable, a SOP
// class that is no recording, a transfer syntax endorecon does not decode, Rows or Columns not
// positive, a Number of Frames that is no whole number or more than the pixel data's bytes.
InstanceHeader LoadInstanceHeader(const std::filesystem::path& path);

// The DICOM files of `path` (a file, or a folder's files) loaded and grouped by series, each
// series' instances in Instance Number order and the series in Series Number order. In a folder,
// DICOM files of other classes (a DICOMDIR, a CT, a report: what a CD export or a study holds beside
// a recording) are skipped with a warning. Throws kNotFound when `path` does not exist, FailInvalid
// for a folder with no recording (naming what was skipped) and LoadInstanceHeader's errors.
std::vector<std::vector<InstanceHeader>> LoadSeriesHeaders(const std::filesystem::path& path);

// Throws FailInvalid naming `path` unless the series fit `stereo`: one series, or two of one study,
// of different Series Numbers (the lower the left eye), as many frames and one size for --stereo
// series.
void CheckSeriesFitLayout(const std::vector<std::vector<InstanceHeader>>& series, StereoLayout stereo,
                          const std::filesystem::path& path);

// The frames of a series: its instances' Number of Frames summed.
int SeriesFrames(const std::vector<InstanceHeader>& series);

// One eye's width and height in a frame of `columns` x `rows` under `stereo` (half the width side by
// side, half the height top-bottom). Throws FailInvalid naming `where` for an odd width or height
// that cannot be halved.
FrameSize EyeSize(StereoLayout stereo, int columns, int rows, const std::string& where);

}  // namespace endorecon::dicom
