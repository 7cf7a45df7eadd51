// The messages of a hand-made Upload stream, for tests that send exactly what they mean to
// (a manifest, then chunks), bad forms included.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "common/sha256.h"
#include "endorecon/v1/job_service.pb.h"

namespace endorecon::testing {

// The manifest entry of a file holding `bytes`.
inline v1::FileEntry Entry(const std::string& path, const std::string& bytes) {
  v1::FileEntry entry;
  entry.set_path(path);
  entry.set_size(static_cast<std::int64_t>(bytes.size()));
  entry.set_sha256(Sha256Hex(bytes));
  return entry;
}

// The first message of an upload stream.
inline v1::UploadRequest ManifestOf(const std::vector<v1::FileEntry>& entries) {
  v1::UploadRequest request;
  for (const auto& entry : entries) *request.mutable_manifest()->add_files() = entry;
  return request;
}

inline v1::UploadRequest Chunk(const std::string& path, std::int64_t offset, const std::string& data) {
  v1::UploadRequest request;
  request.mutable_chunk()->set_path(path);
  request.mutable_chunk()->set_offset(offset);
  request.mutable_chunk()->set_data(data);
  return request;
}

}  // namespace endorecon::testing
