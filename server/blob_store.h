// Content-addressed file storage: <root>/blobs/<first two hex>/<sha256>. A blob appears only
// complete and verified. Its bytes first accumulate in a partial, which survives restarts (so an
// upload resumes from what it committed), and is fsynced, checked against the digest and renamed into
// place; a mismatch removes the partial, so nothing half-written is visible. Each tenant uploads into
// partials of its own, <root>/partial/<sha256>.<tenant>.part (<sha256>.part for the server's own,
// admins' and workers of every tenant): a digest that checks out then says that the tenant sent every
// byte itself, which is what BlobHolders takes as proof that it holds the content.
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
  // Bytes held for `entry`: its size when the blob exists, otherwise the length of `owner`'s partial.
  std::int64_t Committed(const v1::FileEntry& entry, const std::string& owner = "") const;
  // The length of `owner`'s partial of `entry` (0 when there is none), whether or not the blob exists:
  // what an uploader that must send the content again (BlobHolders) has sent of it.
  std::int64_t PartialBytes(const v1::FileEntry& entry, const std::string& owner = "") const;

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
    Writer(BlobStore& store, const v1::FileEntry& entry, std::string name);
    BlobStore& store_;
    v1::FileEntry entry_;
    std::string name_;  // the partial's (PartialName)
    std::filesystem::path partial_;
    int fd_ = -1;
    std::int64_t committed_ = 0;
    std::int64_t written_back_ = 0;  // bytes handed to the kernel's writeback (write-behind)
    Sha256 digest_;
  };
  // Opens `owner`'s partial of `entry` (a tenant; "" for the server's own). Throws kFailedPrecondition
  // when another stream is writing that partial right now.
  std::unique_ptr<Writer> OpenWriter(const v1::FileEntry& entry, const std::string& owner = "");
  // The same, but waits up to `wait` for another writer of the partial to finish, then returns null
  // instead of throwing.
  std::unique_ptr<Writer> TryOpenWriter(const v1::FileEntry& entry,
                                        std::chrono::milliseconds wait = std::chrono::milliseconds(0),
                                        const std::string& owner = "");

  // Promotes `owner`'s partial of `entry` when it already holds every byte (the server died between
  // the last write and the rename: no client sends more for it, so nothing else would), also when
  // the blob exists already. Returns whether it promoted it now: false for a partial not full, none,
  // or one another stream writes. Throws as Promote.
  bool PromoteIfFull(const v1::FileEntry& entry, const std::string& owner = "");

  // Makes the server's own partial of `sha256` (<sha256>.part) `owner`'s, when it has none and neither
  // is being written: an upload of before 2026-12-06, when every tenant's went there. Returns whether
  // it did.
  bool AdoptPartial(const std::string& sha256, const std::string& owner);

  // Deletes the blob (retention); a missing blob is not an error. Throws Error(kUnavailable) when
  // the file exists but cannot be removed.
  void Remove(const std::string& sha256);

  // Whether the blob's bytes still hash to its digest (reads it whole); false for a missing blob.
  bool Intact(const std::string& sha256) const;
  // Takes a damaged blob (its bytes no longer hash to its digest: a disk fault, a file cut short)
  // out of the store, to <root>/damaged/<sha256>.<Unix seconds> for an admin to look at, so that
  // the next upload of the content stores it anew; logs an error naming `what` (a file's path in a
  // clip). Returns where it went. A damaged copy left in place was sent to every worker and refused
  // every upload of the content as "already on the server" (found 2026-12-06).
  std::filesystem::path SetAsideDamaged(const std::string& sha256, const std::string& what);
  // How many files lie set aside as damaged (an admin deletes them once the disk is checked).
  std::size_t DamagedCount() const;
  // Whether a copy of `sha256` lies set aside as damaged.
  bool WasSetAside(const std::string& sha256) const;

  // Stores `bytes` as a blob at once; returns its digest.
  std::string Put(std::string_view bytes);

  // A file the store holds: a blob, or the partial of an upload (none being written right now).
  struct StoredFile {
    std::string sha256;
    std::filesystem::path path;
    bool partial = false;
    std::string owner;  // a partial's tenant ("": the server's own)
    std::int64_t bytes = 0;
    std::filesystem::file_time_type written;  // last modified
  };
  std::vector<StoredFile> Files() const;
  // Deletes what Files() listed, unless a writer opened its partial since; missing is not an error.
  // Throws Error(kUnavailable) when the file exists but cannot be removed.
  void Remove(const StoredFile& file);

  const std::filesystem::path& root() const { return root_; }

 private:
  // "<sha256>" or "<sha256>.<owner>": the partial's file name without ".part", and what writing_ holds.
  static std::string PartialName(const std::string& sha256, const std::string& owner);
  std::filesystem::path PartialPath(const std::string& name) const;
  void Release(const std::string& name);

  std::filesystem::path root_;
  mutable std::mutex mutex_;
  std::condition_variable released_;
  std::set<std::string> writing_;  // the partials open in a Writer, by PartialName
};

}  // namespace endorecon::server
