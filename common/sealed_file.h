// Binary files that carry their own checksum (checkpoints, models): an 8-byte magic whose last byte is
// the format version, the body, then the SHA-256 of magic and body as 64 hex characters. Any flipped,
// lost or added byte is found before a single value is used. Written through WriteFileWith (a reader
// never sees half a file).
#pragma once

#include <filesystem>
#include <fstream>
#include <functional>
#include <ostream>
#include <string_view>

namespace endorecon {

// Throws as WriteFileWith.
void WriteSealedFile(const std::filesystem::path& path, const char (&magic)[8],
                     const std::function<void(std::ostream&)>& body, std::string_view what);

// Opens a sealed file for reading and returns the stream positioned at the body. Throws
// Error(kNotFound) when it cannot be read, Error(kInvalidArgument) when it is not a `what` file (other
// magic) or one of another format version (both named), Error(kDataLoss) when it is truncated or its
// checksum does not match. Every message names the file.
std::ifstream OpenSealedFile(const std::filesystem::path& path, const char (&magic)[8],
                             std::string_view what);

}  // namespace endorecon
