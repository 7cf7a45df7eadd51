// Opening a file to read it, with the system's reason when it cannot be opened: "cannot open the file"
// alone left a user guessing at an unreadable image (found 2026-12-06).
#pragma once

#include <filesystem>
#include <fstream>

namespace endorecon {

// `path` opened for binary reading. Throws Error(kInvalidArgument): "PATH: cannot open the file
// (Permission denied)".
std::ifstream OpenToRead(const std::filesystem::path& path);

}  // namespace endorecon
