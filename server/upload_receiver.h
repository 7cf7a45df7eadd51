// The receiving side of uploads (JobService.Upload from clients, WorkerService.PutBlobs from
// workers): a manifest first, then chunks continuing each file from its committed size.
// Rejections: no manifest first or a second manifest, an unsafe or unknown path, a chunk over
// 4 MiB or past its file's size (INVALID_ARGUMENT); an upload over the size limit, or one that
// would leave less than the reserve free on the data disk (RESOURCE_EXHAUSTED, before any byte is
// written, and again before every chunk: a disk that fills from elsewhere mid-stream stops the
// stream there, its committed bytes kept for the resume once space is freed); a write the disk
// refuses anyway (ENOSPC: RESOURCE_EXHAUSTED naming the file); a wrong digest (DATA_LOSS; the bytes
// are discarded). The reserve keeps room for the job store and for the results of accepted jobs. A stream
// that ends early keeps its committed bytes for the next one. Chunks of a file that another stream is writing
// at the same moment are skipped; the returned status then says the upload is incomplete and the client asks
// again.
//
// Memory: at most `max_streams` streams receive chunks at once (all uploads, clients' and
// workers'); the others wait after their manifest, and their bytes wait in their senders, held
// back by HTTP/2 flow control (the server runs without gRPC's BDP probing, which would otherwise
// widen every waiting stream's window to megabytes). A hundred clients uploading 10 MiB each at
// once peaked at ~900 MB resident without the slots and ~290 MB with 16, at the same throughput
// (docs/benchmarks.md).
#pragma once

#include <grpcpp/support/sync_stream.h>

#include <chrono>
#include <cstdint>
#include <functional>
#include <mutex>
#include <semaphore>
#include <set>
#include <string>

#include "common/warning_pacer.h"
#include "endorecon/v1/files.pb.h"
#include "server/blob_store.h"
#include "server/upload_owner.h"

namespace endorecon::server {

// Who uploads: a client's clip, or a worker's checkpoint and results (which keep only a quarter
// of the reserve: the reserve is there for them).
enum class Uploader { kClient, kWorker };

class UploadReceiver {
 public:
  // `on_bytes` is told every committed chunk's size (for the metrics).
  UploadReceiver(BlobStore& blobs, std::int64_t max_upload_bytes, std::int64_t min_free_bytes,
                 int max_streams, std::function<void(std::int64_t)> on_bytes);

  // Validates `manifest` (and, for a client, the size limit) and says how much of each file is
  // committed for `owner`. A sizes-only manifest (no digests: IsSizesOnly) is checked against the
  // limit only and answered with its total.
  v1::UploadStatus Query(const v1::Manifest& manifest, Uploader uploader,
                         const UploadOwner& owner = {}) const;
  // Runs one blocking Read of the stream (a StallWatch's Guard); returns what the Read returned.
  using ReadGuard = std::function<bool(const std::function<bool()>& read)>;
  // Consumes one upload stream. Throws Error as described above. `admit`, when given, sees the
  // manifest before any byte is written and throws to refuse it (a tenant's quota). `guard`, when
  // given, runs each Read (the manifest's and every chunk's), so a sender that stops cannot keep its
  // thread or its slot. `cancelled`, when given, is asked while the stream waits for an upload slot:
  // a call cancelled or past its deadline stops waiting (CANCELLED), so it holds no thread.
  v1::UploadStatus Receive(grpc::ServerReaderInterface<v1::UploadRequest>& reader, Uploader uploader,
                           const UploadOwner& owner = {},
                           const std::function<void(const v1::Manifest&)>& admit = {},
                           const ReadGuard& guard = {}, const std::function<bool()>& cancelled = {});

 private:
  // Refuses `bytes` more that would leave less than the reserve free.
  void CheckSpace(std::int64_t bytes, Uploader uploader) const;
  // Query with the unproven contents already asked for.
  v1::UploadStatus Status(const v1::Manifest& manifest, Uploader uploader, const std::string& tenant,
                          const std::set<std::string>& unproven) const;

  BlobStore& blobs_;
  std::int64_t max_upload_bytes_;
  std::int64_t min_free_bytes_;
  std::counting_semaphore<> slots_;
  std::function<void(std::int64_t)> on_bytes_;
  // A worker's upload refused for space is said in the server's log, once a minute at most (the
  // worker tries again every 10 s): it was said to the worker alone (found 2026-12-07).
  mutable std::mutex space_warning_mutex_;
  mutable WarningPacer space_warnings_{std::chrono::minutes(1)};
};

}  // namespace endorecon::server
