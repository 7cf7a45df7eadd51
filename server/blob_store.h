// Content-addressed file storage: <root>/blobs/<first two hex>/<sha256>. A blob appears only
// complete and verified. Its bytes first accumulate in <root>/partial/<sha256>.part, which survives
// restarts (so an upload resumes from what it committed), and is fsynced, checked against the
// digest and renamed into place; a mismatch removes the partial, so nothing half-written is visible.
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include "common/sha256.h"
#include "endorecon/v1/files.pb.h"

namespace endorecon::server {

class BlobStore {
 public:
  // Creates the folders under `root` if missing.
  explicit BlobStore(std::filesystem::path root);

  bool Has(const std::string& sha256) const;
  // The blob's file. Throws Error(kNotFound) naming the digest when it is absent.
  std::filesystem::path PathOf(const std::string& sha256) const;
  // The blob's size; nullopt when it is absent (one stat, where Has and PathOf take one each).
  std::optional<std::int64_t> SizeOf(const std::string& sha256) const;
  // Bytes held for `entry`: its size when the blob exists, otherwise the partial's length.
  std::int64_t Committed(const v1::FileEntry& entry) const;

  // Appends to the partial of one entry, then promotes it. One writer per digest at a time.
  class Writer {
   public:
    ~Writer();  // fsyncs what was appended and releases the digest
    Writer(const Writer&) = delete;
    Writer& operator=(const Writer&) = delete;
    std::int64_t committed() const { return committed_; }
    bool full() const { return committed_ == entry_.size(); }
    // Throws kFailedPrecondition when `offset` is past the committed size (a gap), kInvalidArgument
    // when the data would run past the entry's size. Bytes before the committed size are skipped.
    void Append(std::int64_t offset, std::string_view data);
    // Requires full(). fsyncs, verifies the digest and renames the partial to the blob. On a
    // mismatch removes the partial and throws kDataLoss naming the path and both digests.
    void Promote();

   private:
    friend class BlobStore;
    Writer(BlobStore& store, const v1::FileEntry& entry);
    BlobStore& store_;
    v1::FileEntry entry_;
    std::filesystem::path partial_;
    int fd_ = -1;
    std::int64_t committed_ = 0;
    std::int64_t written_back_ = 0;  // bytes handed to the kernel's writeback (write-behind)
    Sha256 digest_;
  };
  // Throws kFailedPrecondition when another stream is writing the same content right now.
  std::unique_ptr<Writer> OpenWriter(const v1::FileEntry& entry);
  // The same, but waits up to `wait` for another writer of the content to finish, then returns
  // null instead of throwing.
  std::unique_ptr<Writer> TryOpenWriter(const v1::FileEntry& entry,
                                        std::chrono::milliseconds wait = std::chrono::milliseconds(0));

  // Promotes the partial of `entry` when it already holds every byte (the server died between the
  // last write and the rename: no client sends more for it, so nothing else would). Returns whether
  // the blob exists now; false also while another stream writes the content. Throws as Promote.
  bool PromoteIfFull(const v1::FileEntry& entry);

  // Deletes the blob (retention); a missing blob is not an error. Throws Error(kUnavailable) when
  // the file exists but cannot be removed.
  void Remove(const std::string& sha256);

  // Stores `bytes` as a blob at once; returns its digest.
  std::string Put(std::string_view bytes);

  // A file the store holds: a blob, or the partial of an upload (none being written right now).
  struct StoredFile {
    std::string sha256;
    std::filesystem::path path;
    bool partial = false;
    std::int64_t bytes = 0;
    std::filesystem::file_time_type written;  // last modified
  };
  std::vector<StoredFile> Files() const;
  // Deletes what Files() listed, unless a writer opened its partial since; missing is not an error.
  // Throws Error(kUnavailable) when the file exists but cannot be removed.
  void Remove(const StoredFile& file);

  const std::filesystem::path& root() const { return root_; }

 private:
  std::filesystem::path PartialPath(const std::string& sha256) const;
  void Release(const std::string& sha256);

  std::filesystem::path root_;
  mutable std::mutex mutex_;
  std::condition_variable released_;
  std::set<std::string> writing_;
};

}  // namespace endorecon::server
