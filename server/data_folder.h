// Checks of a data folder (--data-dir) before the server or `endorecon-server token` uses it.
#pragma once

#include <filesystem>
#include <string>

namespace endorecon::server {

// Throws Error(kFailedPrecondition) when `data_dir` holds no store (jobs.sqlite, or the tokens.sqlite
// of tokens made before the server's first start) but the folder above it, or a folder in it, does: a
// --data-dir moved one folder down (the Kubernetes manifest's did on 2026-12-06, from the volume's root,
// which fsGroup makes group-owned, to /data/endorecon) or back up (a rollback, or a unit file left behind).
// Started there, the server began an empty store beside the real one, its jobs unlisted and, without the
// tokens beside them, every API open to every caller; `token create` made a second token store that the move
// of the data then overwrote.
void RefuseAStoreBesideIt(const std::filesystem::path& data_dir);

// Throws Error(kFailedPrecondition) when `data_dir`'s blobs/ holds files but its jobs.sqlite is
// missing, empty, or holds no table and has no write-ahead log (a restore that copied the blobs and
// not the store, the store to another name, or a running server's store without its log): a new
// store would have no job reference them, and retention would delete every one as no job's. Before
// the server starts, and before `retention --dry-run` reads (its store open made the missing table).
void RefuseBlobsWithoutTheirStore(const std::filesystem::path& data_dir);

// Throws Error(kFailedPrecondition) when this process runs as root and `data_dir` exists and belongs
// to another user: every file root made there (server.lock, orphans.json, a store's -wal, a token
// store) would be root's, which the folder's user's server cannot open. Root passes every permission
// check, so the refusals of files the server's user cannot use never came (found 2026-12-07).
// `program` says what refuses ("endorecon-server", "token create").
void RefuseRootInAnotherUsersFolder(const std::filesystem::path& data_dir, const std::string& program);

}  // namespace endorecon::server
