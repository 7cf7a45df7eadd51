#include "server/file_sender.h"

#include <fstream>
#include <string>

#include "common/error.h"
#include "common/transport_security.h"

namespace endorecon::server {

std::int64_t SendFiles(const BlobStore& blobs,
                       const std::vector<std::pair<v1::FileEntry, std::int64_t>>& files,
                       grpc::ServerWriterInterface<v1::FileChunk>& writer, StallWatch& watch,
                       grpc::ServerContext* context) {
  std::int64_t sent = 0;
  std::string buffer(kChunkBytes, '\0');
  for (const auto& [entry, start] : files) {
    if (start < 0 || start > entry.size()) {
      FailInvalid("offset " + std::to_string(start) + " of '" + entry.path() + "' is outside its " +
                  std::to_string(entry.size()) + " bytes");
    }
    std::ifstream in(blobs.PathOf(entry.sha256()), std::ios::binary);
    in.seekg(start);
    std::int64_t offset = start;
    bool first = true;
    while (first || offset < entry.size()) {
      const auto want =
          static_cast<std::streamsize>(std::min<std::int64_t>(kChunkBytes, entry.size() - offset));
      in.read(buffer.data(), want);
      if (in.gcount() != want)
        Fail(ErrorCode::kDataLoss, "blob of '" + entry.path() + "' is shorter than its entry");
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
