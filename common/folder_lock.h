// One process per folder: two servers on one data folder would both schedule the same jobs and both
// run retention; two workers on one scratch folder would delete each other's running jobs (each
// clears what an earlier run left at its start). The lock is an flock on a file in the folder,
// which holds the holder's process id; the kernel drops it when the process ends, however it ends,
// so a folder whose lock nobody holds was left by a process that is gone.
#pragma once

#include <filesystem>
#include <string>

namespace endorecon {

class FolderLock {
 public:
  // Locks `folder`/`file`. Throws Error(kFailedPrecondition) "another PROGRAM (process N) uses the
  // KIND FOLDER; one PROGRAM per KIND" when another process holds it.
  FolderLock(const std::filesystem::path& folder, const std::string& file, const std::string& program,
             const std::string& kind);
  ~FolderLock();
  FolderLock(const FolderLock&) = delete;
  FolderLock& operator=(const FolderLock&) = delete;

 private:
  int fd_ = -1;
};

// Whether `lock_file` exists and no process holds its lock (without taking it for long).
bool LockAbandoned(const std::filesystem::path& lock_file);

}  // namespace endorecon
