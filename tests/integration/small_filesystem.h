// A small filesystem for the full-disk tests: a tmpfs of a given size mounted on a folder (needs
// root or CAP_SYS_ADMIN; without, mounted() is false and why() says so), and a filler file that
// leaves a given number of bytes free.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>

namespace endorecon::testing {

class SmallFilesystem {
 public:
  SmallFilesystem(const std::filesystem::path& dir, std::int64_t bytes);
  ~SmallFilesystem();  // detaches the mount (lazily: a process may still hold files on it)
  SmallFilesystem(const SmallFilesystem&) = delete;
  SmallFilesystem& operator=(const SmallFilesystem&) = delete;

  bool mounted() const { return mounted_; }
  const std::string& why() const { return why_; }
  std::int64_t available() const;

 private:
  std::filesystem::path dir_;
  bool mounted_ = false;
  std::string why_;
};

// Appends zeros to `path` until its filesystem has at most `leave` bytes free; returns the bytes
// written.
std::int64_t FillLeaving(const std::filesystem::path& path, std::int64_t leave);

}  // namespace endorecon::testing
