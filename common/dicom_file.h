// Whether a path is meant as a DICOM recording, told from the bytes and names alone (no DCMTK), so
// the thin CLI can refuse a file that is not one before uploading it.
#pragma once

#include <filesystem>

namespace endorecon::dicom {

// True when `path` is a file that starts with a DICOM preamble ("DICM" at byte 128).
bool IsDicomFile(const std::filesystem::path& path);
// True when `path` is named *.dcm (any case).
bool HasDicomExtension(const std::filesystem::path& path);
// True when `path` is meant as a recording: a DICOM file or a file named *.dcm, or a folder with
// one of those directly inside it (ReadRecording then says what is wrong with a file that is not DICOM)
// that is no clip folder (transforms.json or poses_bounds.npy: common/clip_files.h).
bool HoldsDicom(const std::filesystem::path& path);

}  // namespace endorecon::dicom
