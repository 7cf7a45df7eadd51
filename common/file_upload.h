// The sending side of an upload (the CLI's clips, the worker's checkpoints and results): ask what
// the server already holds, then stream only the missing bytes, each file from its committed size.
#pragma once

#include <grpcpp/client_context.h>
#include <grpcpp/support/sync_stream.h>

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>

#include "endorecon/v1/files.pb.h"

namespace endorecon {

// The two calls of an upload service (JobService QueryUpload/Upload, WorkerService
// QueryBlobs/PutBlobs), bound to a stub.
struct UploadCalls {
  std::function<grpc::Status(grpc::ClientContext*, const v1::Manifest&, v1::UploadStatus*)> query;
  std::function<std::unique_ptr<grpc::ClientWriterInterface<v1::UploadRequest>>(grpc::ClientContext*,
                                                                                v1::UploadStatus*)>
      open;
};

struct UploadOptions {
  std::chrono::milliseconds call_timeout{30000};  // for the query, and added to the stream's deadline
  double min_bytes_per_second = 1 << 20;          // the stream's deadline allows this slowest rate
  // ... and this many files a second (the server makes each a blob: a write, a sync, a rename), so a
  // clip of many small files is not held to its bytes' time alone.
  double min_files_per_second = 50;
  std::function<void(std::int64_t sent, std::int64_t to_send)> on_progress;
  int max_rounds = 5;  // query-and-send rounds while another upload holds a file of the same content
};

struct UploadResult {
  v1::UploadStatus status;         // the server's final word: complete when every file is a blob
  std::int64_t bytes_sent = 0;     // bytes this call streamed
  std::int64_t bytes_skipped = 0;  // bytes the server already held (earlier uploads, same content)
};

// Uploads the files of `manifest`, read from `dir`; the result's status says whether it is
// complete (it is not only if concurrent uploads of the same content kept it busy). Throws Error with the
// server's status (or kNotFound/kDataLoss when a local file is missing or changed since the manifest was
// made).
UploadResult UploadFiles(const std::filesystem::path& dir, const v1::Manifest& manifest,
                         const UploadCalls& calls, const UploadOptions& options);

}  // namespace endorecon
