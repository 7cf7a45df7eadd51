#include "server/upload_receiver.h"

#include <spdlog/spdlog.h>

#include <chrono>
#include <filesystem>
#include <map>
#include <memory>
#include <set>

#include "common/error.h"
#include "common/manifest.h"
#include "common/transport_security.h"

namespace endorecon::server {

UploadReceiver::UploadReceiver(BlobStore& blobs, std::int64_t max_upload_bytes, std::int64_t min_free_bytes,
                               int max_streams, std::function<void(std::int64_t)> on_bytes)
    : blobs_(blobs),
      max_upload_bytes_(max_upload_bytes),
      min_free_bytes_(min_free_bytes),
      slots_(max_streams),
      on_bytes_(std::move(on_bytes)) {}

void UploadReceiver::CheckSpace(std::int64_t bytes, Uploader uploader) const {
  if (bytes <= 0) return;
  const std::int64_t reserve = uploader == Uploader::kClient ? min_free_bytes_ : min_free_bytes_ / 4;
  std::error_code error;
  const auto space = std::filesystem::space(blobs_.root(), error);
  if (error) {
    Fail(ErrorCode::kUnavailable,
         "cannot read the free space of " + blobs_.root().string() + ": " + error.message());
  }
  const auto free_bytes = static_cast<std::int64_t>(space.available);
  if (bytes > free_bytes - reserve) {
    const std::string message =
        "upload needs " + std::to_string(bytes) + " more bytes but the server's data disk has " +
        std::to_string(free_bytes) + " bytes free and keeps " + std::to_string(reserve) +
        (uploader == Uploader::kClient
             ? " of them for the job store and accepted jobs' results (--min-free-bytes)"
             : " of them for the job store (a quarter of --min-free-bytes)") +
        "; committed bytes are kept: retry once space is freed";
    if (uploader == Uploader::kWorker) {
      std::lock_guard lock(space_warning_mutex_);
      int held = 0;
      if (space_warnings_.Due(held)) {
        spdlog::warn(
            "a worker's results or checkpoint were refused: {}; the worker keeps them and tries again: free "
            "space on {}{}",
            message, blobs_.root().string(),
            held > 0 ? " (" + std::to_string(held) + " more refusals since the last warning)" : "");
      }
    }
    Fail(ErrorCode::kResourceExhausted, message);
  }
}

v1::UploadStatus UploadReceiver::Query(const v1::Manifest& manifest, Uploader uploader,
                                       const UploadOwner& owner) const {
  const bool sizes_only = IsSizesOnly(manifest);
  return Status(manifest, uploader, owner.tenant,
                owner.unproven && !sizes_only ? owner.unproven(manifest) : std::set<std::string>{});
}

v1::UploadStatus UploadReceiver::Status(const v1::Manifest& manifest, Uploader uploader,
                                        const std::string& tenant,
                                        const std::set<std::string>& unproven) const {
  const bool sizes_only = IsSizesOnly(manifest);
  ValidateManifest(manifest, sizes_only);
  const std::int64_t total = TotalBytes(manifest);
  // The limit is on what clients send. A worker's results and checkpoints belong to a job the server
  // accepted: refusing them failed the job after its training, once per attempt.
  if (uploader == Uploader::kClient && total > max_upload_bytes_) {
    Fail(ErrorCode::kResourceExhausted,
         "upload of " + std::to_string(total) + " bytes exceeds the server's limit of " +
             std::to_string(max_upload_bytes_) + " bytes (--max-upload-bytes)" + LargestFileNote(manifest) +
             ": send fewer frames (`endorecon submit --frames START:END:STEP` uploads a clip's picked frames "
             "alone) or smaller ones, or ask the server's admin to raise the limit");
  }
  v1::UploadStatus status;
  if (sizes_only) {
    // Before the client hashes its files: only the limit (above) and the caller's quotas are told.
    // The free space is checked by the query with digests, which knows what is stored already.
    status.set_total_bytes(total);
    return status;
  }
  std::int64_t committed = 0;
  for (const auto& entry : manifest.files()) {
    // A stored copy of another size than the file's is damaged (cut short on the disk) unless its bytes
    // still hash to the digest (a client that declared the size wrong, which the submit refuses): set
    // aside, the upload sends the file anew. Left in place it was "already on the server" for good,
    // and the submit blamed the user's intact file (found 2026-12-06).
    if (const auto stored = blobs_.SizeOf(entry.sha256());
        stored && *stored != entry.size() && !blobs_.Intact(entry.sha256())) {
      blobs_.SetAsideDamaged(entry.sha256(), entry.path());
    }
    auto* file = status.add_files();
    file->set_path(entry.path());
    file->set_size(entry.size());
    file->set_committed(unproven.count(entry.sha256()) ? blobs_.PartialBytes(entry, tenant)
                                                       : blobs_.Committed(entry, tenant));
    committed += file->committed();
  }
  CheckSpace(total - committed, uploader);
  status.set_committed_bytes(committed);
  status.set_total_bytes(total);
  bool complete = true;
  for (const auto& entry : manifest.files())
    complete = complete && !unproven.count(entry.sha256()) && blobs_.Has(entry.sha256());
  status.set_complete(complete);
  return status;
}

v1::UploadStatus UploadReceiver::Receive(grpc::ServerReaderInterface<v1::UploadRequest>& reader,
                                         Uploader uploader, const UploadOwner& owner,
                                         const std::function<void(const v1::Manifest&)>& admit,
                                         const ReadGuard& guard, const std::function<bool()>& cancelled) {
  const std::unique_ptr<const UploadOwner, void (*)(const UploadOwner*)> ending(&owner,
                                                                                [](const UploadOwner* o) {
                                                                                  if (o->ended) o->ended();
                                                                                });
  v1::UploadRequest request;
  const auto read = [&] {
    return guard ? guard([&] { return reader.Read(&request); }) : reader.Read(&request);
  };
  if (!read()) FailInvalid("empty upload stream: the first message must be the manifest");
  if (!request.has_manifest()) {
    FailInvalid("the first message of an upload must be its manifest, got a chunk of '" +
                request.chunk().path() + "'");
  }
  const v1::Manifest manifest = request.manifest();
  ValidateManifest(manifest);  // with its digests: a sizes-only manifest is for a query
  // Asked once: a content proven by another stream meanwhile is taken again here, not refused.
  std::set<std::string> unproven = owner.unproven ? owner.unproven(manifest) : std::set<std::string>{};
  Status(manifest, uploader, owner.tenant, unproven);
  if (admit) admit(manifest);
  std::map<std::string, const v1::FileEntry*> entries;
  for (const auto& entry : manifest.files()) entries[entry.path()] = &entry;

  while (!slots_.try_acquire_for(std::chrono::milliseconds(200))) {
    if (cancelled && cancelled()) {
      Fail(ErrorCode::kCancelled,
           "upload cancelled (or past its deadline) while it waited for one of the "
           "server's upload slots (--max-uploads)");
    }
  }
  const std::unique_ptr<std::counting_semaphore<>, void (*)(std::counting_semaphore<>*)> slot(
      &slots_, [](std::counting_semaphore<>* slots) { slots->release(); });
  // Stored, as far as this tenant goes.
  const auto stored_for = [&](const v1::FileEntry& entry) {
    return !unproven.count(entry.sha256()) && blobs_.Has(entry.sha256());
  };
  std::unique_ptr<BlobStore::Writer> writer;
  std::string writer_path;
  std::set<std::string> busy;
  while (read()) {
    if (request.has_manifest())
      FailInvalid("a second manifest in one upload stream; open a new stream instead");
    const auto& chunk = request.chunk();
    const auto found = entries.find(chunk.path());
    if (found == entries.end()) FailInvalid("chunk of '" + chunk.path() + "', which is not in the manifest");
    if (chunk.data().size() > static_cast<std::size_t>(kChunkBytes)) {
      FailInvalid("chunk of '" + chunk.path() + "' carries " + std::to_string(chunk.data().size()) +
                  " bytes; at most " + std::to_string(kChunkBytes) + " per chunk");
    }
    const v1::FileEntry& entry = *found->second;
    if (stored_for(entry) || busy.count(entry.path())) continue;
    if (writer_path != entry.path()) {
      writer.reset();
      writer_path.clear();
      // A stream that was just cut may still hold the file for a moment; a concurrent upload of the
      // same content holds it longer, and then the client asks again later.
      writer = blobs_.TryOpenWriter(entry, std::chrono::seconds(2), owner.tenant);
      if (writer && stored_for(entry)) {
        writer.reset();
        continue;
      }
      if (!writer) {
        busy.insert(entry.path());
        continue;
      }
      writer_path = entry.path();
    }
    CheckSpace(static_cast<std::int64_t>(chunk.data().size()), uploader);
    writer->Append(chunk.offset(), chunk.data());
    if (on_bytes_) on_bytes_(static_cast<std::int64_t>(chunk.data().size()));
    if (writer->full()) {
      const auto promoting = std::move(writer);
      writer_path.clear();
      promoting->Promote();
      unproven.erase(entry.sha256());
      if (owner.proven) owner.proven(entry.sha256());
    }
  }
  writer.reset();
  // A file whose bytes all arrived before a server crash is sent no more: promote it here (they are
  // the tenant's partial's, so they prove as much as a promotion above).
  for (const auto& entry : manifest.files()) {
    if (busy.count(entry.path()) || stored_for(entry)) continue;
    if (blobs_.PromoteIfFull(entry, owner.tenant) && owner.proven) owner.proven(entry.sha256());
  }
  return Query(manifest, uploader, owner);
}

}  // namespace endorecon::server
