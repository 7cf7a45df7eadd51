// The workers an admin drained, kept across server restarts: <data-dir>/drains.json,
//
//   {"draining": {"gpu-node-7": 1765000000000}}
//
// each drained worker's id with when it was last seen (Unix ms), written whole at every change
// (common/file_write.h), read once at start. Without it a server restart (an upgrade in a maintenance
// window) put every drained worker back in service.
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <string>

namespace endorecon::server {

using Drains = std::map<std::string, std::int64_t>;  // worker id -> last seen, Unix ms

// The drains in `file`; none when it does not exist. Throws Error(kInvalidArgument) naming the file
// and what is wrong for one that is no such JSON.
Drains ReadDrains(const std::filesystem::path& file);
// Throws as WriteFile (common/file_write.h).
void WriteDrains(const std::filesystem::path& file, const Drains& drains);

}  // namespace endorecon::server
