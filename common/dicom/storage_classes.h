// The SOP classes and transfer syntaxes endorecon takes in when it retrieves a study (recording.h),
// for the presentation contexts of C-GET (as SCP role) and of the storage SCP: a recording's, and
// those of endorecon's own results, which a study holds once results went back into it. Those are
// taken (a PACS fails a whole C-GET or C-MOVE when one instance has no context) and dropped.
#pragma once

#include <string>
#include <utility>
#include <vector>

class DcmItem;

namespace endorecon::dicom {

struct StorageClass {
  std::string sop_class;
  std::vector<std::string> transfer_syntaxes;  // in order of preference
};

// Video classes with the MPEG-2, MPEG-4 AVC/H.264 and HEVC syntaxes; image classes with
// uncompressed, RLE and JPEG (baseline, extended, lossless) syntaxes.
const std::vector<StorageClass>& RecordingStorageClasses();

// Whether `data` is a result endorecon wrote (result_instances.h): made by endorecon, of a result's
// class. A recording endorecon wrote (`to-dicom`) is not.
bool IsEndoreconResult(DcmItem& data);

}  // namespace endorecon::dicom
