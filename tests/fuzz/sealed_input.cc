#include "tests/fuzz/sealed_input.h"

#include "common/sha256.h"

namespace endorecon::fuzz {

std::string SealedFileOf(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return {};
  std::string file(reinterpret_cast<const char*>(data) + 1, size - 1);
  if (data[0] % 2 == 1) file += Sha256Hex(file);
  return file;
}

}  // namespace endorecon::fuzz
