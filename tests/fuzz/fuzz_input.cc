#include "tests/fuzz/fuzz_input.h"

#include <fcntl.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>

#include "tests/unit/temp_dir.h"

namespace endorecon::fuzz {

const std::filesystem::path& ScratchDir() {
  static const testing::TempDir dir("fuzz");
  return dir.path();
}

std::filesystem::path WriteInput(const std::string& name, std::string_view bytes) {
  const std::filesystem::path path = ScratchDir() / name;
  // Plain POSIX calls: the harness must not depend on the code it tests to set up its inputs.
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0600);
  if (fd < 0) Broken("cannot write the input file " + path.string());
  for (std::size_t done = 0; done < bytes.size();) {
    const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (n <= 0) Broken("cannot write the input file " + path.string());
    done += static_cast<std::size_t>(n);
  }
  ::close(fd);
  return path;
}

void Broken(const std::string& what) {
  std::fprintf(stderr, "==fuzz contract== %s\n", what.c_str());
  std::abort();
}

}  // namespace endorecon::fuzz
