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

// Throws Error(kInvalidArgument) naming the entry unless every path passes CheckRelativePath,
// paths are unique, sizes are non-negative and digests are 64 lowercase hex characters.
void ValidateManifest(const v1::Manifest& manifest);

std::int64_t TotalBytes(const v1::Manifest& manifest);

}  // namespace endorecon
