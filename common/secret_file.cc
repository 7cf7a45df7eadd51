#include "common/secret_file.h"

#include <fmt/format.h>
#include <sys/stat.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <sstream>

#include "common/error.h"
#include "common/file_read.h"
#include "common/filesystem_failure.h"

namespace endorecon {
namespace {

// A file `error` (errno) kept from being read: missing (NOT_FOUND), or there but refused, with the
// reason and the user. A key owned by root (0600) read by the server's user, or a file in a folder
// this user may not enter, was "NOT_FOUND", as a missing file (found 2026-12-07).
[[noreturn]] void FailUnreadable(const std::filesystem::path& path, const std::string& flag, int error) {
  if (error == ENOENT || error == ENOTDIR)
    Fail(ErrorCode::kNotFound, flag + " " + path.string() + ": no such file");
  FailInvalid(flag + " " + path.string() + ": cannot be read: " + std::strerror(error) + RunsAsNote(error));
}

std::string ReadWhole(const std::filesystem::path& path, const std::string& flag) {
  try {
    RequireRegularFile(path);
  } catch (const Error& e) {
    FailInvalid(flag + " " + e.what());
  }
  errno = 0;
  std::ifstream in(path, std::ios::binary);
  if (!in) FailUnreadable(path, flag, errno != 0 ? errno : ENOENT);
  std::ostringstream bytes;
  bytes << in.rdbuf();
  // There, but of no use: a bad argument (exit 2), not a missing one (exit 3).
  if (bytes.str().empty()) FailInvalid(flag + " " + path.string() + ": the file is empty");
  return bytes.str();
}

}  // namespace

std::string ReadSecretFile(const std::filesystem::path& path, const std::string& flag) {
  struct stat info {};
  if (::stat(path.c_str(), &info) != 0) FailUnreadable(path, flag, errno);
  // Its kind before its mode: a FIFO's 0644 was reported as a secret others may read.
  if (!S_ISREG(info.st_mode)) ReadWhole(path, flag);
  if ((info.st_mode & S_IRWXO) != 0) {
    FailInvalid(
        fmt::format("{} {}: the file holds a secret but others may access it (mode {:04o}); "
                    "run: chmod 600 {}",
                    flag, path.string(), info.st_mode & 07777, path.string()));
  }
  return ReadWhole(path, flag);
}

std::string ReadPublicFile(const std::filesystem::path& path, const std::string& flag) {
  std::string pem = ReadWhole(path, flag);
  // A file of other text reached gRPC, which failed the channel as "empty address list" (found
  // 2026-12-06).
  if (pem.find("-----BEGIN CERTIFICATE-----") == std::string::npos) {
    FailInvalid(flag + " " + path.string() +
                ": holds no PEM certificate (no \"-----BEGIN CERTIFICATE-----\" line)");
  }
  return pem;
}

}  // namespace endorecon
