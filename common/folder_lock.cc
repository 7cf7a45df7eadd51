#include "common/folder_lock.h"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <string>

#include "common/error.h"

namespace endorecon {

FolderLock::FolderLock(const std::filesystem::path& folder, const std::string& file,
                       const std::string& program, const std::string& kind) {
  const auto path = folder / file;
  fd_ = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0600);
  if (fd_ < 0) {
    const int error = errno;
    Fail(ErrorCode::kFailedPrecondition,
         "cannot open " + path.string() + ": " + std::strerror(error) +
             (error == EACCES || error == EPERM
                  ? " (owned by another user? chown it, or the folder with -R, to this program's user)"
                  : ""));
  }
  if (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
    const int error = errno;
    char holder[32] = {};
    const ssize_t n = ::pread(fd_, holder, sizeof holder - 1, 0);
    ::close(fd_);
    fd_ = -1;
    if (error != EWOULDBLOCK)
      Fail(ErrorCode::kFailedPrecondition, "cannot lock " + path.string() + ": " + std::strerror(error));
    std::string pid = n > 0 ? std::string(holder, static_cast<std::size_t>(n)) : "";
    while (!pid.empty() && (pid.back() == '\n' || pid.back() == ' ')) pid.pop_back();
    Fail(ErrorCode::kFailedPrecondition,
         "another " + program + (pid.empty() ? std::string() : " (process " + pid + ")") + " uses the " +
             kind + " " + folder.string() + "; one " + program + " per " + kind);
  }
  const std::string pid = std::to_string(::getpid()) + "\n";
  if (::ftruncate(fd_, 0) != 0 || ::pwrite(fd_, pid.data(), pid.size(), 0) < 0) {
    // The lock holds without the id; only the message for a second process would lack it.
  }
}

FolderLock::~FolderLock() {
  if (fd_ >= 0) ::close(fd_);
}

bool LockAbandoned(const std::filesystem::path& lock_file) {
  const int fd = ::open(lock_file.c_str(), O_RDONLY | O_CLOEXEC | O_NOFOLLOW);
  if (fd < 0) return false;
  const bool abandoned = ::flock(fd, LOCK_EX | LOCK_NB) == 0;
  ::close(fd);  // and so unlocked
  return abandoned;
}

}  // namespace endorecon
