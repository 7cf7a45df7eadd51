#include "common/filesystem_failure.h"

#include <pwd.h>
#include <unistd.h>

#include <cerrno>
#include <string>

namespace endorecon {

std::string DescribeFilesystemError(const std::filesystem::filesystem_error& error) {
  std::string text = error.path1().empty() ? std::string("a file") : error.path1().string();
  if (!error.path2().empty()) text += " and " + error.path2().string();
  return text + ": " + error.code().message() + RunsAsNote(error.code().value());
}

bool IsUsersFileProblem(int error) {
  switch (error) {
    case EACCES:
    case EPERM:
    case ENOENT:
    case ENOTDIR:
    case EISDIR:
    case ELOOP:
    case ENAMETOOLONG:
    case EROFS:
      return true;
    default:
      return false;
  }
}

std::string RunsAsNote(int error) {
  if (error != EACCES && error != EPERM) return "";
  const uid_t uid = ::geteuid();
  passwd entry{};
  passwd* user = nullptr;
  char buffer[1024];  // getpwuid_r: a worker's devices may ask at once
  ::getpwuid_r(uid, &entry, buffer, sizeof buffer, &user);
  return " (this command runs as user " + (user ? std::string(user->pw_name) : "uid " + std::to_string(uid)) +
         ")";
}

}  // namespace endorecon
