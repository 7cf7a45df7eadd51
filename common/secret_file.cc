#include "common/secret_file.h"

#include <fmt/format.h>
#include <sys/stat.h>

#include <fstream>
#include <sstream>

#include "common/error.h"

namespace endorecon {
namespace {

std::string ReadWhole(const std::filesystem::path& path, const std::string& flag) {
  std::ifstream in(path, std::ios::binary);
  if (!in) Fail(ErrorCode::kNotFound, flag + " " + path.string() + ": cannot be read");
  std::ostringstream bytes;
  bytes << in.rdbuf();
  // There, but of no use: a bad argument (exit 2), not a missing one (exit 3).
  if (bytes.str().empty()) FailInvalid(flag + " " + path.string() + ": the file is empty");
  return bytes.str();
}

}  // namespace

std::string ReadSecretFile(const std::filesystem::path& path, const std::string& flag) {
  struct stat info {};
  if (::stat(path.c_str(), &info) != 0)
    Fail(ErrorCode::kNotFound, flag + " " + path.string() + ": no such file");
  if ((info.st_mode & S_IRWXO) != 0) {
    FailInvalid(
        fmt::format("{} {}: the file holds a secret but others may access it (mode {:04o}); "
                    "run: chmod 600 {}",
                    flag, path.string(), info.st_mode & 07777, path.string()));
  }
  return ReadWhole(path, flag);
}

std::string ReadPublicFile(const std::filesystem::path& path, const std::string& flag) {
  return ReadWhole(path, flag);
}

}  // namespace endorecon
