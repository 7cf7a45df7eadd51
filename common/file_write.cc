#include "common/file_write.h"

#include <cerrno>
#include <cstring>
#include <fstream>
#include <string>
#include <system_error>

#include "common/error.h"

namespace endorecon {
namespace {

[[noreturn]] void FailWrite(const std::filesystem::path& path, std::string_view what, int error) {
  const ErrorCode code =
      error == ENOSPC || error == EDQUOT ? ErrorCode::kResourceExhausted : ErrorCode::kUnavailable;
  Fail(code, "cannot write " + std::string(what) + " " + path.string() +
                 (error != 0 ? std::string(": ") + std::strerror(error) : std::string()));
}

}  // namespace

void WriteFileWith(const std::filesystem::path& path, const std::function<void(std::ostream&)>& body,
                   std::string_view what) {
  std::error_code ec;
  if (path.has_parent_path()) std::filesystem::create_directories(path.parent_path(), ec);
  if (ec) FailWrite(path, what, ec.value());
  const std::filesystem::path temp = path.string() + ".tmp";
  int error = 0;
  {
    std::ofstream out(temp, std::ios::binary | std::ios::trunc);
    if (!out) FailWrite(path, what, errno);
    body(out);
    out.flush();
    if (!out) error = errno != 0 ? errno : EIO;
  }
  if (error == 0) {
    std::filesystem::rename(temp, path, ec);
    if (!ec) return;
    error = ec.value();
  }
  std::filesystem::remove(temp, ec);
  FailWrite(path, what, error);
}

void WriteFile(const std::filesystem::path& path, std::string_view bytes, std::string_view what) {
  WriteFileWith(
      path, [&](std::ostream& out) { out.write(bytes.data(), static_cast<std::streamsize>(bytes.size())); },
      what);
}

}  // namespace endorecon
