#include "common/safe_path.h"

#include <string>

#include "common/error.h"

namespace endorecon {
namespace {

[[noreturn]] void Reject(std::string_view path, const char* why) {
  std::string message("file path '");
  message.append(path.substr(0, 256));
  message.append("' ");
  message.append(why);
  FailInvalid(message);
}

}  // namespace

void CheckRelativePath(std::string_view path) {
  if (path.empty()) Reject(path, "is empty");
  if (path.size() > 4096) Reject(path, "is longer than 4096 bytes");
  if (path.front() == '/') Reject(path, "is absolute; paths must be relative to the upload");
  if (path.find('\\') != std::string_view::npos || path.find('\0') != std::string_view::npos) {
    Reject(path, "contains a backslash or NUL");
  }
  std::size_t start = 0;
  while (start <= path.size()) {
    const std::size_t end = std::min(path.find('/', start), path.size());
    const std::string_view segment = path.substr(start, end - start);
    if (segment.empty() || segment == "." || segment == "..")
      Reject(path, "has an empty, '.' or '..' segment");
    start = end + 1;
  }
}

}  // namespace endorecon
