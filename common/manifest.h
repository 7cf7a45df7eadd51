// Manifests: the list of (relative path, size, SHA-256) that names a clip, a checkpoint or a
// result set everywhere in the service.
#pragma once

#include <cstdint>
#include <filesystem>
#include <nlohmann/json_fwd.hpp>
#include <string>
#include <string_view>
#include <vector>

#include "endorecon/v1/files.pb.h"

namespace endorecon {

// Every regular file under `dir` (recursively), sorted by path, with its size and SHA-256.
// Throws Error(kNotFound) if `dir` is not a directory, kInvalidArgument if it holds no file.
v1::Manifest ManifestOfDirectory(const std::filesystem::path& dir);
// The same without the digests (sha256 empty): what a sizes-only QueryUpload sends before the
// files are read, so a clip over a limit is refused before its hours of hashing.
v1::Manifest ListingOfDirectory(const std::filesystem::path& dir);
// The same for `files` under `dir` (each `dir` / relative path, as ListClipFiles gives them), sorted
// by path. Throws Error(kInvalidArgument) for a path the server would refuse, naming it.
v1::Manifest ListingOfFiles(const std::filesystem::path& dir, std::vector<std::filesystem::path> files);
// Fills in the SHA-256 of every entry, reading `root`/path.
void AddDigests(const std::filesystem::path& root, v1::Manifest& manifest);

// No file of a clip or a result is larger (1 PiB); a manifest naming one is refused.
inline constexpr std::int64_t kMaxFileBytes = std::int64_t{1} << 50;

// Throws Error(kInvalidArgument) naming the entry unless every path passes CheckRelativePath,
// paths are unique, sizes are in [0, kMaxFileBytes] and digests are 64 lowercase hex characters
// (or, with `sizes_only`, every digest is empty).
void ValidateManifest(const v1::Manifest& manifest, bool sizes_only = false);
// Whether `text` is a SHA-256 as manifests carry it: 64 lowercase hex characters.
bool IsSha256Hex(std::string_view text);
// Whether `manifest` is a sizes-only listing (some files, and no digest in any of them).
bool IsSizesOnly(const v1::Manifest& manifest);

// The most bytes a manifest with its digests may take: one call carries it, in the service's messages
// (transport_security.h kMaxMessageBytes) with room for the rest of the call.
std::size_t MostManifestBytes();
// The bytes a results folder's manifest takes per frame of its clip: rgb/, depth/ (.npy and .png),
// error/ and pointcloud/, and with uncertainty maps uncertainty/'s six files a frame. 1,054 and
// 1,081 counted on the results of 200 and 48 frames (the run's own files spread over its frames);
// a 3,813-frame job's results took 4,348,147 bytes in its Complete call, 1,140 a frame; rounded
// up. About 500 without uncertainty/ (an 8,388-frame job's results went through).
inline constexpr std::size_t kResultManifestBytesPerFrame = 1200;
inline constexpr std::size_t kResultManifestBytesPerFrameWithoutUncertainty = 500;
// Throws Error(kInvalidArgument) when the results of a clip of `frames` frames, beside the clip's own
// manifest of `clip_manifest_bytes` (a job's status carries both), would need more than
// MostManifestBytes(): a run that could not hand its results back, a job `status` and `fetch` could
// not show (a 3,813-frame job succeeded and could not be fetched; found 2026-12-06). Names `where`,
// the frames and about how many of this clip's fit, with uncertainty maps and without.
void CheckResultsFit(std::size_t frames, bool uncertainty, std::size_t clip_manifest_bytes,
                     const std::string& where);
// Whether a job of this training configuration (its --config keys, as the job carries them) writes
// uncertainty maps: every preset does, unless the keys set mc_passes 0. A resumed job's are its first
// run's, so the checkpoint need not be read to tell.
bool WritesUncertaintyMaps(const nlohmann::json& config);

// The sum of the sizes, saturated at the largest int64 (so it is over every limit, never negative).
std::int64_t TotalBytes(const v1::Manifest& manifest);
// " (its largest file: PATH, N bytes)", the end of a refusal by size, so the user knows where to look;
// "" for a manifest without files.
std::string LargestFileNote(const v1::Manifest& manifest);

}  // namespace endorecon
