// Damage inside a SQLite write-ahead log that SQLite itself passes over in silence. SQLite replays a
// WAL frame by frame and stops at the first frame whose checksum fails, taking it for the torn end of
// an interrupted write: the committed transactions after it are dropped without a word. A flipped
// bit in the middle of jobs.sqlite-wal lost 7 of 15 accepted jobs that way, the server started
// normally, and retention then deleted their uploads as no job's (found 2026-12-06).
//
// A torn write can only leave frames that no commit follows (SQLite syncs a commit's frames before it
// reports the commit), so a frame that fails its checksum followed by a frame of the same log (its
// salts) that verifies and ends a transaction is damage, not a crash. Read here by hand: SQLite has no
// call that reports it. The format: https://www.sqlite.org/fileformat2.html, "The WAL File Format".
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>

namespace endorecon::server {

struct WalDamage {
  std::int64_t bad_frame = 0;         // the first frame (from 0) whose checksum fails; -1: the header's
  std::int64_t commits_after = 0;     // committed transactions of the same log after it
};

// Reads `wal` (absent, empty or no WAL: nullopt). Never throws for its contents; kUnavailable when it
// exists but cannot be read.
std::optional<WalDamage> FindWalDamage(const std::filesystem::path& wal);

}  // namespace endorecon::server
