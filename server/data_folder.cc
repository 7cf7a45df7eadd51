#include "server/data_folder.h"

#include "common/error.h"

namespace endorecon::server {

void RefuseAStoreBesideIt(const std::filesystem::path& data_dir) {
  namespace fs = std::filesystem;
  std::error_code error;
  if (fs::exists(data_dir / "jobs.sqlite", error)) return;
  const fs::path parent = fs::absolute(data_dir, error).parent_path();
  if (!error && fs::exists(parent / "jobs.sqlite", error)) {
    Fail(ErrorCode::kFailedPrecondition,
         "--data-dir " + data_dir.string() + " has no job store, but its parent " + parent.string() +
             " has one (jobs.sqlite): a --data-dir moved one folder down? Starting here would begin an empty "
             "store beside it. Stop the server and move that folder's files into " + data_dir.string() +
             " (docs/operations.md, \"Kubernetes\"), or point --data-dir at " + parent.string());
  }
  for (const auto& entry : fs::directory_iterator(data_dir, error)) {
    std::error_code inner;
    if (!entry.is_directory(inner) || !fs::exists(entry.path() / "jobs.sqlite", inner)) continue;
    Fail(ErrorCode::kFailedPrecondition,
         "--data-dir " + data_dir.string() + " has no job store, but its folder " + entry.path().string() +
             " has one (jobs.sqlite): point --data-dir at it (the Kubernetes manifest's data folder is "
             "/data/endorecon since 2026-12-06). Starting here would begin an empty store beside it, without "
             "its tokens");
  }
}

}  // namespace endorecon::server
