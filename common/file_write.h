// Writing a whole file so that a reader never sees half of it: the bytes go to `path`.tmp, are
// flushed and checked, and the temporary file is renamed over `path`. Every failure (a folder that
// cannot be made, no space, a read-only disk) throws Error naming the file; the temporary is removed.
#pragma once

#include <filesystem>
#include <functional>
#include <ostream>
#include <string_view>

namespace endorecon {

// Creates the parent folders. Throws Error(kResourceExhausted) when the disk is full, Error(kUnavailable)
// for any other write failure; the message names `what` (e.g. "metrics") and the path.
void WriteFile(const std::filesystem::path& path, std::string_view bytes, std::string_view what = "file");

// As WriteFile, with the contents streamed by `body` (binary).
void WriteFileWith(const std::filesystem::path& path, const std::function<void(std::ostream&)>& body,
                   std::string_view what = "file");

}  // namespace endorecon
