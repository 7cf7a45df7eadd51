// Manifests: the list of (relative path, size, SHA-256) that names a clip, a checkpoint or a
// result set everywhere in the service.
#pragma once

#include <cstdint>
#include <filesystem>

#include "endorecon/v1/files.pb.h"

namespace endorecon {

// Every regular file under `dir` (recursively), sorted by path, with its size and SHA-256.
// Throws Error(kNotFound) if `dir` is not a directory, kInvalidArgument if it holds no file.
v1::Manifest ManifestOfDirectory(const std::filesystem::path& dir);

// No file of a clip or a result is larger (1 PiB); a manifest naming one is refused.
inline constexpr std::int64_t kMaxFileBytes = std::int64_t{1} << 50;

// Throws Error(kInvalidArgument) naming the entry unless every path passes CheckRelativePath,
// paths are unique, sizes are in [0, kMaxFileBytes] and digests are 64 lowercase hex characters.
void ValidateManifest(const v1::Manifest& manifest);

// The sum of the sizes, saturated at the largest int64 (so it is over every limit, never negative).
std::int64_t TotalBytes(const v1::Manifest& manifest);

}  // namespace endorecon
