// What an image file's bytes say before any decoder sees them: shared by the worker, which decodes
// (worker/engine/scene/image_file.h), and the CLI, which checks a clip's files before its upload.
#pragma once

#include <filesystem>

namespace endorecon {

// Throws FailInvalid naming the file when it is missing or empty, when its first bytes are not those
// of a PNG, JPEG, BMP or TIFF file (whatever its name says), when it is a PNG whose chunks end before
// its IEND chunk (a truncated file: an interrupted copy or upload), declare an impossible length, are
// no chunk (zero padding) or fail their CRC, or when it is a JPEG with no end-of-image marker after its
// scan. Both are read whole, without decoding. Bytes after IEND or EOI are allowed, as decoders allow them.
void CheckImageBytes(const std::filesystem::path& path);

}  // namespace endorecon
