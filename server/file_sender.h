// The sending side of downloads (JobService.Fetch, WorkerService.GetBlobs): blob content as
// FileChunks, each file from a requested offset, its entry (size, sha256) on its first chunk.
#pragma once

#include <grpcpp/server_context.h>
#include <grpcpp/support/sync_stream.h>

#include <cstdint>
#include <utility>
#include <vector>

#include "endorecon/v1/files.pb.h"
#include "server/blob_store.h"
#include "server/stall_watch.h"

namespace endorecon::server {

// Sends each (entry, offset), every chunk's Write watched by `watch` (a receiver that stops reading
// has its call cancelled). Each file's stored bytes are hashed on their way (a resumed one's from its
// start) and its last chunk is sent only when they match its digest; a blob of another size than the
// entry's, or whose bytes do not match, is set aside (BlobStore::SetAsideDamaged) and refused as
// kDataLoss naming the file. Throws kInvalidArgument for an offset past a file's size, kNotFound for
// a missing blob, kUnavailable when the receiver went away or stalled. Returns the bytes sent.
std::int64_t SendFiles(BlobStore& blobs, const std::vector<std::pair<v1::FileEntry, std::int64_t>>& files,
                       grpc::ServerWriterInterface<v1::FileChunk>& writer, StallWatch& watch,
                       grpc::ServerContext* context);

}  // namespace endorecon::server
