// The SOP classes and transfer syntaxes endorecon takes in as a recording (recording.h), for the
// presentation contexts of C-GET (as SCP role) and of the storage SCP.
#pragma once

#include <string>
#include <utility>
#include <vector>

namespace endorecon::dicom {

struct StorageClass {
  std::string sop_class;
  std::vector<std::string> transfer_syntaxes;  // in order of preference
};

// Video classes with the MPEG-2, MPEG-4 AVC/H.264 and HEVC syntaxes; image classes with
// uncompressed, RLE and JPEG (baseline, extended, lossless) syntaxes.
const std::vector<StorageClass>& RecordingStorageClasses();

}  // namespace endorecon::dicom
