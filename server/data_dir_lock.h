// One server per data folder: two servers on the same job store and blobs would both schedule the
// same jobs and both run retention. The lock is an flock on <data dir>/server.lock, which holds the
// holder's process id; the kernel drops it when the process ends, however it ends.
#pragma once

#include <filesystem>

namespace endorecon::server {

class DataDirLock {
 public:
  // Throws Error(kFailedPrecondition) naming the folder and the other server's process id when
  // another process holds the lock.
  explicit DataDirLock(const std::filesystem::path& data_dir);
  ~DataDirLock();
  DataDirLock(const DataDirLock&) = delete;
  DataDirLock& operator=(const DataDirLock&) = delete;

 private:
  int fd_ = -1;
};

}  // namespace endorecon::server
