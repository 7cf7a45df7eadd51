#include "common/file_upload.h"

#include <algorithm>
#include <fstream>
#include <map>
#include <set>
#include <string>
#include <thread>

#include "common/error.h"
#include "common/file_read.h"
#include "common/grpc_status.h"
#include "common/manifest.h"
#include "common/transport_security.h"

namespace endorecon {
namespace {

// Streams [offset, size) of one file as chunks; false when the server ended the stream early.
bool SendFile(const std::filesystem::path& file, const v1::FileEntry& entry, std::int64_t offset,
              grpc::ClientWriterInterface<v1::UploadRequest>& writer, UploadResult& result,
              const UploadOptions& options, std::int64_t to_send) {
  RequireRegularFile(file);
  std::ifstream in(file, std::ios::binary);
  if (!in) Fail(ErrorCode::kNotFound, "cannot read " + file.string());
  in.seekg(offset);
  v1::UploadRequest request;
  auto* chunk = request.mutable_chunk();
  chunk->set_path(entry.path());
  std::string buffer(kChunkBytes, '\0');
  while (offset < entry.size()) {
    const auto want =
        static_cast<std::streamsize>(std::min<std::int64_t>(kChunkBytes, entry.size() - offset));
    in.read(buffer.data(), want);
    if (in.gcount() != want) Fail(ErrorCode::kDataLoss, file.string() + " is shorter than its manifest size");
    chunk->set_offset(offset);
    chunk->set_data(buffer.data(), static_cast<std::size_t>(want));
    if (!writer.Write(request)) return false;
    offset += want;
    result.bytes_sent += want;
    if (options.on_progress) options.on_progress(result.bytes_sent, to_send);
  }
  return true;
}

// Opens one Upload stream and sends the missing bytes of every file, each from its committed size.
void SendRound(const std::filesystem::path& dir, const v1::Manifest& manifest, const UploadCalls& calls,
               const UploadOptions& options, UploadResult& result) {
  std::map<std::string, std::int64_t> committed;
  for (const auto& file : result.status.files()) committed[file.path()] = file.committed();
  const std::int64_t to_send = result.status.total_bytes() - result.status.committed_bytes();
  const auto files_to_send =
      std::count_if(manifest.files().begin(), manifest.files().end(),
                    [&](const v1::FileEntry& entry) { return committed[entry.path()] < entry.size(); });
  const auto stream_timeout =
      options.call_timeout +
      std::chrono::milliseconds(static_cast<std::int64_t>(
          1000.0 * (static_cast<double>(to_send) / options.min_bytes_per_second +
                    static_cast<double>(files_to_send) / options.min_files_per_second)));
  auto context = CallContext(stream_timeout);
  v1::UploadStatus final_status;
  auto writer = calls.open(context.get(), &final_status);
  v1::UploadRequest first;
  *first.mutable_manifest() = manifest;
  bool open = writer->Write(first);
  // A content sent whole once in this stream is not sent again for another path (the server keeps one
  // blob a content: 3,000 hard links of one frame went up as 7.1 GB; found 2026-12-06).
  std::set<std::string> sent;
  for (const auto& entry : manifest.files()) {
    if (!open) break;
    const std::int64_t offset = committed[entry.path()];
    if (offset >= entry.size() || sent.count(entry.sha256())) continue;
    open = SendFile(dir / entry.path(), entry, offset, *writer, result, options, to_send);
    if (open) sent.insert(entry.sha256());
  }
  if (open) writer->WritesDone();
  ThrowIfFailed(writer->Finish(), "upload");
  result.status = final_status;
}

}  // namespace

UploadResult UploadFiles(const std::filesystem::path& dir, const v1::Manifest& manifest,
                         const UploadCalls& calls, const UploadOptions& options) {
  UploadResult result;
  // A round sends what the server lacks; another round is needed only when a concurrent upload of
  // the same content held a file (the server skips it) and did not finish it.
  for (int round = 0; round < options.max_rounds; ++round) {
    if (round > 0) std::this_thread::sleep_for(std::chrono::milliseconds(200 * round));
    auto query_context = CallContext(options.call_timeout);
    ThrowIfFailed(calls.query(query_context.get(), manifest, &result.status), "upload query");
    if (round == 0) result.bytes_skipped = result.status.committed_bytes();
    if (result.status.complete()) return result;
    SendRound(dir, manifest, calls, options, result);
    if (result.status.complete()) return result;
  }
  return result;
}

}  // namespace endorecon
