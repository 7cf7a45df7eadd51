#include "server/data_folder.h"

#include <pwd.h>
#include <sys/stat.h>
#include <unistd.h>

#include <fstream>
#include <string_view>

#include "common/error.h"
#include "server/access_failure.h"

namespace endorecon::server {
namespace {

namespace fs = std::filesystem;

// The store `dir` holds: "jobs.sqlite", else "tokens.sqlite" (tokens made before the server's first
// start), else "".
std::string StoreIn(const fs::path& dir) {
  std::error_code error;
  for (const char* file : {"jobs.sqlite", "tokens.sqlite"}) {
    if (fs::exists(dir / file, error)) return file;
  }
  return "";
}

// Whether the SQLite database `file` holds no table in its main file and has no write-ahead log with
// anything in it: a store copied without its -wal while the server ran (every job was still in the
// log) reads as one never used. Read by hand, before SQLite opens (and would set up) anything: the
// file's header, then page 1's b-tree header, whose cell count is the schema's entries (sqlite.org
// "Database File Format" 1.3, 1.6).
bool HoldsNoTable(const std::filesystem::path& file) {
  std::error_code error;
  const auto wal = file.string() + "-wal";
  if (std::filesystem::exists(wal, error) && std::filesystem::file_size(wal, error) > 0) return false;
  std::ifstream in(file, std::ios::binary);
  char bytes[105] = {};
  if (!in.read(bytes, sizeof bytes)) return false;
  if (std::string_view(bytes, 16) != std::string_view("SQLite format 3\0", 16)) return false;
  const int cells = (static_cast<unsigned char>(bytes[103]) << 8) | static_cast<unsigned char>(bytes[104]);
  return cells == 0;
}

}  // namespace

void RefuseAStoreBesideIt(const std::filesystem::path& data_dir) {
  if (!StoreIn(data_dir).empty()) return;
  std::error_code error;
  const fs::path parent = fs::absolute(data_dir, error).parent_path();
  if (const auto store = error ? "" : StoreIn(parent); !store.empty()) {
    Fail(ErrorCode::kFailedPrecondition,
         "--data-dir " + data_dir.string() + " has no store, but its parent " + parent.string() +
             " has one (" + store +
             "): a --data-dir moved one folder down? Starting here would begin an empty store beside it. "
             "Stop the server and move that folder's files into " +
             data_dir.string() + " (docs/operations.md, \"Kubernetes\"), or point --data-dir at " +
             parent.string());
  }
  for (const auto& entry : fs::directory_iterator(data_dir, error)) {
    std::error_code inner;
    if (!entry.is_directory(inner)) continue;
    const auto store = StoreIn(entry.path());
    if (store.empty()) continue;
    Fail(ErrorCode::kFailedPrecondition,
         "--data-dir " + data_dir.string() + " has no store, but its folder " + entry.path().string() +
             " has one (" + store +
             "): point --data-dir at it (the Kubernetes manifest's data folder is /data/endorecon since "
             "2026-12-06). Starting here would begin an empty store beside it, without its tokens");
  }
}

// A data folder whose blobs/ holds files but whose jobs.sqlite is missing, empty or holds no table (a
// restore that copied the blobs and not the store, the store to another name, or the store without
// its write-ahead log): a new store would have no job reference them, and the first retention sweep
// deleted every one as an orphan (found 2026-12-05; without the log, 2026-12-07).
void RefuseBlobsWithoutTheirStore(const std::filesystem::path& data_dir) {
  namespace fs = std::filesystem;
  std::error_code error;
  const fs::path store = data_dir / "jobs.sqlite";
  const bool no_store = !fs::exists(store, error) || fs::file_size(store, error) == 0 || HoldsNoTable(store);
  if (!no_store || !fs::is_directory(data_dir / "blobs", error)) return;
  for (fs::recursive_directory_iterator it(data_dir / "blobs", error), end; !error && it != end;
       it.increment(error)) {
    if (!it->is_regular_file(error)) continue;
    Fail(ErrorCode::kFailedPrecondition,
         data_dir.string() + ": blobs/ holds files (" + it->path().filename().string() +
             ", ...) but there is no job store (jobs.sqlite is missing, empty, or holds no table and "
             "no write-ahead log: copied without its jobs.sqlite-wal while the server ran?), so "
             "retention would delete them as no job's: restore jobs.sqlite beside them, taken with "
             "`sqlite3 jobs.sqlite \".backup FILE\"` (docs/operations.md, \"Backup and restore\"), or "
             "move blobs/ away to start afresh");
  }
  // A blobs/ this user cannot list (a restore chowned without -R) passed as empty.
  if (error) FailAccess((data_dir / "blobs").string() + ": this user cannot list it", error.value());
}

void RefuseRootInAnotherUsersFolder(const std::filesystem::path& data_dir, const std::string& program) {
  struct stat folder {};
  if (geteuid() != 0 || ::stat(data_dir.c_str(), &folder) != 0 || folder.st_uid == 0) return;
  const passwd* owner = getpwuid(folder.st_uid);
  const std::string name = owner ? owner->pw_name : std::to_string(folder.st_uid);
  Fail(ErrorCode::kFailedPrecondition,
       data_dir.string() + " belongs to user " + name + " (uid " + std::to_string(folder.st_uid) + "), and " +
           program + " runs as root: the files it made there would be root's, which a server run as " + name +
           " cannot open. Run it as " + name + " (runuser -u " + name + " -- ...), or chown -R root " +
           "the folder to run the server as root");
}

}  // namespace endorecon::server
