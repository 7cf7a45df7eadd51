#include "tests/integration/small_filesystem.h"

#include <sys/mount.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <vector>

namespace endorecon::testing {

SmallFilesystem::SmallFilesystem(const std::filesystem::path& dir, std::int64_t bytes) : dir_(dir) {
  std::filesystem::create_directories(dir_);
  const std::string options = "size=" + std::to_string(bytes) + ",mode=0755";
  if (::mount("endorecon-test", dir_.c_str(), "tmpfs", MS_NOSUID | MS_NODEV, options.c_str()) != 0) {
    why_ = "cannot mount a tmpfs on " + dir_.string() + " (" + std::strerror(errno) +
           "): the full-disk tests need root or CAP_SYS_ADMIN";
    return;
  }
  mounted_ = true;
}

SmallFilesystem::~SmallFilesystem() {
  if (mounted_) ::umount2(dir_.c_str(), MNT_DETACH);
}

std::int64_t SmallFilesystem::available() const {
  return static_cast<std::int64_t>(std::filesystem::space(dir_).available);
}

std::int64_t FillLeaving(const std::filesystem::path& path, std::int64_t leave) {
  const auto free_bytes = static_cast<std::int64_t>(std::filesystem::space(path.parent_path()).available);
  std::int64_t left = free_bytes - leave, written = 0;
  std::ofstream out(path, std::ios::binary | std::ios::app);
  const std::vector<char> zeros(1 << 16, 0);
  while (left > 0 && out) {
    const auto n = std::min<std::int64_t>(left, static_cast<std::int64_t>(zeros.size()));
    out.write(zeros.data(), static_cast<std::streamsize>(n));
    left -= n;
    written += n;
  }
  out.flush();
  return written;
}

}  // namespace endorecon::testing
