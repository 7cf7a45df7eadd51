// Which tenant's uploads brought which content that no job of it holds yet: a tenant's byte quota
// (max_bytes) counts its uploads not yet submitted, not only its jobs' files. Without this, a tenant
// could leave any number of uploads unsubmitted, each under its quota, for --orphan-hours (found
// 2026-12-06). `endorecon uploads` lists it, and drops a tenant's. Kept in <data-dir>/uploads.json
// (KeepIn), written whole at every change, so a server restart neither forgets nor frees them:
//
//   {"uploads": [{"tenant": "radiology", "sha256": "3f9c...", "bytes": 1048576,
//                 "noted_unix_ms": 1765000000000, "proven": true}]}
//
// `proven`: the tenant's upload sent every byte of the content, digest checked (BlobHolders); entries
// without it (a file of before 2026-12-06) are settled at the first start (SettleLegacy).
//
// Not thread-safe: the coordinator holds its lock.
#pragma once

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "endorecon/v1/files.pb.h"

namespace endorecon::server {

class UploadLedger {
 public:
  using Time = std::filesystem::file_time_type;  // the clock of retention's orphan cutoff

  // Reads `file` when it exists (one that cannot be read is warned of and left aside: the server
  // starts, and the uploads from before count again when resumed), then writes it at every change.
  void KeepIn(const std::filesystem::path& file);

  // The bytes `tenant`'s uploads not yet submitted bring, leaving out the files of `except` (an
  // upload resumed, or the manifest being submitted, is not counted twice).
  std::int64_t PendingBytes(const std::string& tenant, const v1::Manifest& except) const;
  // When the last of `tenant`'s uploads not yet submitted was noted (Unix ms); 0 when it has none.
  std::int64_t LastNotedUnixMs(const std::string& tenant) const;
  // `tenant` uploads the files of `manifest` that are no blob yet (`stored` says which are): they count
  // as its until submitted or forgotten. A file noted again is dated anew.
  template <typename Stored>
  void Note(const std::string& tenant, const v1::Manifest& manifest, Stored&& stored, Time now) {
    bool added = false;
    for (const auto& file : manifest.files()) {
      if (!stored(file.sha256())) added = Add(tenant, file, now) || added;
    }
    if (added) Save();
  }
  // `tenant`'s upload sent every byte of the content, digest checked; kept across restarts (Proven).
  // Written at most once a second (kProvenSaveInterval), and by Flush: written at each file, the
  // ledger's whole file made an upload of N files write O(N^2) bytes (10,001 files missed the
  // client's deadline; found 2026-12-06). A server crash forgets at most the last second's, whose
  // files the tenant's next upload sends again.
  void NoteProven(const std::string& tenant, const std::string& sha256);
  // Writes what NoteProven has not written yet (an upload stream's end).
  void Flush();
  // Each (tenant, sha256) noted proven and not yet submitted, dropped or forgotten.
  std::vector<std::pair<std::string, std::string>> Proven() const;
  // How many tenants' uploads not yet submitted bring this content.
  std::size_t Noters(const std::string& sha256) const;
  // Settles the entries read from a file of before 2026-12-06 (no `proven`): each is proven as
  // `proven(tenant, sha256)` says; the file is written once.
  void SettleLegacy(const std::function<bool(const std::string& tenant, const std::string& sha256)>& proven);
  // A job of `tenant` now holds the files of `manifest` (submitted): they count as the job's.
  void Submitted(const std::string& tenant, const v1::Manifest& manifest);
  // Forgets what was last noted before `cutoff`: retention deletes those partial uploads and unused
  // blobs then. Returns how many entries went.
  std::size_t ForgetBefore(Time cutoff);

  struct Pending {
    std::int64_t files = 0;
    std::int64_t bytes = 0;
    std::int64_t last_unix_ms = 0;
  };
  // Each tenant's uploads not yet submitted (tenants with none are left out).
  std::map<std::string, Pending> Tenants() const;
  // `tenant`'s uploads not yet submitted: each content's sha256 and bytes.
  std::vector<std::pair<std::string, std::int64_t>> Files(const std::string& tenant) const;
  // Forgets `tenant`'s; returns the digests it had noted.
  std::vector<std::string> Drop(const std::string& tenant);
  // Whether some tenant's upload not yet submitted, noted at `since` or later, brings this content.
  bool Holds(const std::string& sha256, Time since = Time::min()) const;

 private:
  struct Entry {
    std::int64_t bytes = 0;
    Time noted;
    std::int64_t noted_unix_ms = 0;  // the same moment, for messages
    bool proven = false;             // NoteProven
    bool legacy = false;             // read without `proven` (Legacy)
  };
  bool Add(const std::string& tenant, const v1::FileEntry& file, Time now);  // false: nothing to note
  static Pending Summary(const std::map<std::string, Entry>& files);         // one tenant's
  // Writes the file given to KeepIn, if any; a failure is logged (the ledger in memory holds).
  void Save();

  static constexpr std::chrono::seconds kProvenSaveInterval{1};

  std::map<std::string, std::map<std::string, Entry>> tenants_;  // tenant -> sha256 -> entry
  std::filesystem::path file_;
  bool unsaved_ = false;  // NoteProven marked an entry the file does not have yet
  std::chrono::steady_clock::time_point saved_at_;
};

}  // namespace endorecon::server
