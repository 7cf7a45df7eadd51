#include "server/file_sender.h"

#include <cerrno>
#include <filesystem>
#include <fstream>
#include <string>

#include "common/error.h"
#include "common/sha256.h"
#include "common/transport_security.h"
#include "server/access_failure.h"

namespace endorecon::server {
namespace {

// The blob of `entry` is damaged: set aside (BlobStore::SetAsideDamaged) and refused as DATA_LOSS.
[[noreturn]] void Damaged(BlobStore& blobs, const v1::FileEntry& entry, const std::string& found) {
  blobs.SetAsideDamaged(entry.sha256(), entry.path());
  Fail(ErrorCode::kDataLoss,
       "the server's stored copy of '" + entry.path() + "' (sha256 " + entry.sha256() + ") is damaged: " +
           found + " (a disk fault?); it was set aside, and an upload of the file stores it anew");
}

}  // namespace

std::int64_t SendFiles(BlobStore& blobs, const std::vector<std::pair<v1::FileEntry, std::int64_t>>& files,
                       grpc::ServerWriterInterface<v1::FileChunk>& writer, StallWatch& watch,
                       grpc::ServerContext* context) {
  std::int64_t sent = 0;
  std::string buffer(kChunkBytes, '\0');
  for (const auto& [entry, start] : files) {
    if (start < 0 || start > entry.size()) {
      FailInvalid("offset " + std::to_string(start) + " of '" + entry.path() + "' is outside its " +
                  std::to_string(entry.size()) + " bytes");
    }
    const auto stored = blobs.SizeOf(entry.sha256());
    if (!stored) {
      Fail(ErrorCode::kNotFound,
           "'" + entry.path() + "' (sha256 " + entry.sha256() + ") is not in the server's store");
    }
    if (*stored != entry.size()) {
      Damaged(blobs, entry,
              "it holds " + std::to_string(*stored) + " bytes of the file's " + std::to_string(entry.size()));
    }
    const std::filesystem::path path = blobs.PathOf(entry.sha256());
    std::ifstream in(path, std::ios::binary);
    if (!in.is_open()) {
      // Not read is not damaged: a file another user owns (a restore whose chown missed the files)
      // was hashed as no bytes, set aside as damaged and its job failed (found 2026-12-07).
      FailAccess("the server cannot read its stored copy of '" + entry.path() + "' (" + path.string() + ")",
                 errno);
    }
    // Every byte is hashed as it is read, the bytes before a resumed download's offset too, and the
    // last chunk goes out only once the digest matches: a damaged copy never arrives whole.
    Sha256 digest;
    for (std::int64_t skipped = 0; skipped < start;) {
      const auto want = static_cast<std::streamsize>(std::min<std::int64_t>(kChunkBytes, start - skipped));
      in.read(buffer.data(), want);
      if (in.gcount() != want) Damaged(blobs, entry, "it cannot be read whole");
      digest.Update(buffer.data(), static_cast<std::size_t>(want));
      skipped += want;
    }
    std::int64_t offset = start;
    bool first = true;
    while (first || offset < entry.size()) {
      const auto want =
          static_cast<std::streamsize>(std::min<std::int64_t>(kChunkBytes, entry.size() - offset));
      in.read(buffer.data(), want);
      if (in.gcount() != want) Damaged(blobs, entry, "it cannot be read whole");
      digest.Update(buffer.data(), static_cast<std::size_t>(want));
      if (offset + want == entry.size()) {
        if (const std::string found = digest.HexDigest(); found != entry.sha256())
          Damaged(blobs, entry, "its bytes hash to " + found);
      }
      v1::FileChunk chunk;
      if (first) *chunk.mutable_file() = entry;
      chunk.set_offset(offset);
      chunk.set_data(buffer.data(), static_cast<std::size_t>(want));
      if (!watch.Guard(context, [&] { return writer.Write(chunk); }))
        Fail(ErrorCode::kUnavailable,
             "the receiver went away or stopped reading during '" + entry.path() + "'");
      offset += want;
      sent += want;
      first = false;
    }
  }
  return sent;
}

}  // namespace endorecon::server
