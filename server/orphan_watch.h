// When the server first found each stored file that no job references and no upload brings (an
// orphan: a job's earlier checkpoint, an upload never submitted, results a server refused, a partial
// upload given up). Retention deletes an orphan once it was last written --orphan-hours ago AND was
// first found so --orphan-hours ago: a data folder restored with a job store older than its blobs
// (copies keep the files' times) has its newer jobs' results found as orphans at the first check
// after the restore, and the operator has --orphan-hours from then to notice. Kept in
// <data-dir>/orphans.json (KeepIn), so that a restart does not start the hours again: with the
// hours counted from each start, a server restarted more often than --orphan-hours never deleted
// an orphan (found 2026-12-07).
//
//   {"orphans": [{"path": "blobs/3f/3f9c...", "found_unix_ms": 1765000000000}]}
//
// A file that cannot be read is warned of and left aside (its orphans are found anew: later
// deletion, never earlier). Not thread-safe: the coordinator holds its lock.
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <string>

#include "server/retention.h"

namespace endorecon::server {

class OrphanWatch {
 public:
  // Reads `file` when it exists; Sift writes it when what it holds changes.
  void KeepIn(const std::filesystem::path& file);
  // As KeepIn, never writing (the dry run).
  void ReadFrom(const std::filesystem::path& file);

  // `plan.orphans` and `plan.uploading` are all the store's files no job references (PlanExpiry of
  // every file): notes the ones found now at `now_unix_ms`, forgets those no longer among them
  // (deleted, or a job's now) and those due by `cutoff` (to be deleted), and leaves in plan.orphans
  // only the due ones (the others are counted in plan.orphans_waiting).
  void Sift(RetentionPlan& plan, const OrphanCutoff& cutoff, std::int64_t now_unix_ms);

 private:
  void Read(const std::filesystem::path& file);
  void Save() const;
  // A file's key: its path in the data folder (the folder of the file read), so that `--data-dir d`,
  // `./d` and `/srv/d` name it alike (a restart spelling the folder otherwise found every file anew;
  // found 2026-12-07).
  std::string Key(const std::filesystem::path& path) const;

  std::filesystem::path file_;                 // "" : kept in memory only
  std::filesystem::path root_;                 // the folder of the file read, "" for none
  std::map<std::string, std::int64_t> found_;  // Key -> first found (Unix ms)
};

}  // namespace endorecon::server
