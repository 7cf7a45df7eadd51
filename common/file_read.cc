#include "common/file_read.h"

#include <cerrno>
#include <cstring>
#include <string>

#include "common/error.h"

namespace endorecon {

std::ifstream OpenToRead(const std::filesystem::path& path) {
  errno = 0;
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    FailInvalid(path.string() + ": cannot open the file" +
                (errno ? std::string(" (") + std::strerror(errno) + ")" : ""));
  }
  return in;
}

}  // namespace endorecon
