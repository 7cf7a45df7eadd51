// What an image file's bytes say before any decoder sees them: shared by the worker, which decodes
// (worker/engine/scene/image_file.h), and the CLI, which checks a clip's files before its upload.
#pragma once

#include <filesystem>
#include <optional>

namespace endorecon {

// Throws FailInvalid naming the file when it is missing or empty, when its first bytes are not those
// of a PNG, JPEG, BMP or TIFF file (whatever its name says), when it is a PNG whose chunks end before
// its IEND chunk (a truncated file: an interrupted copy or upload), declare an impossible length, are
// no chunk (zero padding) or fail their CRC, or when it is a JPEG with no end-of-image marker after its
// scan. Both are read whole, without decoding. Bytes after IEND or EOI are allowed, as decoders allow them.
void CheckImageBytes(const std::filesystem::path& path);

// An image's width and height as its header declares them (PNG's IHDR, a JPEG's start-of-frame
// segment, a BMP's info header), read without decoding; nullopt for a TIFF, or a header that does not
// say (a JPEG whose start-of-frame lies past its first MiB, or defers its height). For the CLI's check
// that a clip's frames share one size before its upload.
struct ImageSize {
  int width = 0, height = 0;
};
std::optional<ImageSize> ImageSizeOf(const std::filesystem::path& path);

}  // namespace endorecon
