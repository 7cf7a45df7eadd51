// Inputs for the readers of sealed files (common/sealed_file.h: magic, body, SHA-256 in hex). A
// checksum stops nearly every mutation at the seal, so the first byte of an input picks the mode:
// even, the rest is the file as is (the seal is under test); odd, the rest is magic and body, and
// the harness appends their digest (the body's parser is under test, as if someone had written the
// file on purpose).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

namespace endorecon::fuzz {

// The file an input stands for.
std::string SealedFileOf(const std::uint8_t* data, std::size_t size);

}  // namespace endorecon::fuzz
