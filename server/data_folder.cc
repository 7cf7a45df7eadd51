#include "server/data_folder.h"

#include "common/error.h"

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

}  // namespace endorecon::server
