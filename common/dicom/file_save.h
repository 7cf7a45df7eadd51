// Writing a DICOM file so that a failed write is an error: DCMTK's saveFile ignores a short write and
// a failed close (to-dicom reported "wrote" for a file cut at a size limit, and for -o /dev/full).
// Internal to common/dicom.
#pragma once

#include <dcmtk/dcmdata/dctk.h>

#include <filesystem>

namespace endorecon::dicom {

// Encodes `file` (meta header and dataset) in `xfer` into memory, then writes it with common/file_write.h
// (a temporary beside `path`, flushed, checked and renamed; the folder made). Throws Error(kInternal) when
// DCMTK cannot encode it, kInvalidArgument when `path` exists and is not a regular file (a device, a
// folder), and as WriteFile when the bytes cannot be written.
void SaveFile(DcmFileFormat& file, const std::filesystem::path& path, E_TransferSyntax xfer);

}  // namespace endorecon::dicom
