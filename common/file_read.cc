#include "common/file_read.h"

#include <cerrno>
#include <cstring>
#include <string>

#include "common/error.h"
#include "common/filesystem_failure.h"

namespace endorecon {

void RequireRegularFile(const std::filesystem::path& path, const std::string& what) {
  std::error_code error;
  const auto type = std::filesystem::status(path, error).type();
  using Type = std::filesystem::file_type;
  const char* kind = type == Type::directory                          ? "a folder"
                     : type == Type::fifo                             ? "a named pipe (FIFO)"
                     : type == Type::socket                           ? "a socket"
                     : type == Type::block || type == Type::character ? "a device"
                     : type == Type::unknown                          ? "of an unknown kind"
                                                                      : nullptr;
  if (kind) FailInvalid(path.string() + ": " + kind + ", not a " + what);
}

void RequireExistingFile(const std::filesystem::path& path, const std::string& what) {
  std::error_code error;
  if (!std::filesystem::exists(path, error))
    Fail(ErrorCode::kNotFound, path.string() + ": " + what + " does not exist");
  RequireRegularFile(path, what);
}

std::ifstream OpenToRead(const std::filesystem::path& path) {
  RequireRegularFile(path);
  errno = 0;
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    const int error = errno;
    FailInvalid(path.string() + ": cannot open the file" +
                (error ? std::string(" (") + std::strerror(error) + ")" + RunsAsNote(error) : ""));
  }
  return in;
}

}  // namespace endorecon
