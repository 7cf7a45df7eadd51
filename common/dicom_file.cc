#include "common/dicom_file.h"

#include <algorithm>
#include <cctype>
#include <fstream>
#include <string>
#include <system_error>

#include "common/clip_files.h"
#include "common/file_read.h"

namespace endorecon::dicom {

namespace fs = std::filesystem;

bool IsDicomFile(const fs::path& path) {
  std::error_code error;
  if (!fs::is_regular_file(path, error)) return false;  // a FIFO's read waits for a writer
  std::ifstream in(path, std::ios::binary);
  char magic[4] = {};
  in.seekg(128);
  return in.read(magic, 4) && std::string(magic, 4) == "DICM";
}

bool HasDicomExtension(const fs::path& path) {
  std::string extension = path.extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  return extension == ".dcm";
}

bool HoldsDicom(const fs::path& path) {
  std::error_code error;
  if (fs::is_regular_file(path, error)) return IsDicomFile(path) || HasDicomExtension(path);
  if (!fs::is_directory(path, error)) return false;
  // A clip folder is a clip, whatever else lies in it (a recording kept beside its frames).
  if (FindClipLayout(path)) return false;
  for (const auto& entry : fs::directory_iterator(path, error)) {
    if (entry.is_regular_file() && (IsDicomFile(entry.path()) || HasDicomExtension(entry.path())))
      return true;
  }
  return false;
}

}  // namespace endorecon::dicom
