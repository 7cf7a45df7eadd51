#include "worker/engine/base/machine_memory.h"

#include <algorithm>
#include <fstream>
#include <limits>
#include <optional>
#include <sstream>
#include <vector>

namespace endorecon::base {
namespace {

// A file holding one number ("max" or an unreadable file: none).
std::optional<std::uint64_t> NumberFile(const std::string& path) {
  std::ifstream in(path);
  std::uint64_t value = 0;
  if (!(in >> value)) return std::nullopt;
  return value;
}

// "key value" lines (memory.stat).
std::uint64_t StatField(const std::string& path, const std::string& key) {
  std::ifstream in(path);
  std::string name;
  std::uint64_t value = 0;
  while (in >> name >> value) {
    if (name == key) return value;
  }
  return 0;
}

// "12 kB" -> bytes.
std::uint64_t KibField(const std::string& key) {
  try {
    return static_cast<std::uint64_t>(std::stoull(ProcFileField("/proc/meminfo", key))) * 1024;
  } catch (const std::exception&) {
    return 0;
  }
}

// The cgroup's memory limit less its working set, or nothing without a limit. The process's own
// group first; inside a container's cgroup namespace that path is "/" and the files sit at the root.
std::optional<std::uint64_t> CgroupRoom() {
  std::ifstream in("/proc/self/cgroup");
  std::string v2_path, v1_path;
  for (std::string line; std::getline(in, line);) {
    const auto first = line.find(':'), second = line.find(':', first + 1);
    if (first == std::string::npos || second == std::string::npos) continue;
    const std::string controllers = line.substr(first + 1, second - first - 1);
    const std::string path = line.substr(second + 1);
    if (line.compare(0, first, "0") == 0 && controllers.empty()) v2_path = path;
    std::stringstream list(controllers);
    for (std::string c; std::getline(list, c, ',');) {
      if (c == "memory") v1_path = path;
    }
  }
  struct Layout {
    std::string dir, limit, usage, inactive;  // the files in dir, and memory.stat's key
  };
  std::vector<Layout> tries;
  if (!v1_path.empty()) {
    for (const std::string& dir : {"/sys/fs/cgroup/memory" + v1_path, std::string("/sys/fs/cgroup/memory")})
      tries.push_back({dir, "memory.limit_in_bytes", "memory.usage_in_bytes", "total_inactive_file"});
  } else {
    for (const std::string& dir : {"/sys/fs/cgroup" + v2_path, std::string("/sys/fs/cgroup")})
      tries.push_back({dir, "memory.max", "memory.current", "inactive_file"});
  }
  for (const Layout& l : tries) {
    const std::optional<std::uint64_t> usage = NumberFile(l.dir + "/" + l.usage);
    if (!usage) continue;  // not this group's folder
    const std::optional<std::uint64_t> limit = NumberFile(l.dir + "/" + l.limit);
    // v1 writes "no limit" as a number near 2^63 (rounded to pages).
    if (!limit || *limit >= (std::uint64_t{1} << 62)) return std::nullopt;
    const std::uint64_t inactive = StatField(l.dir + "/memory.stat", l.inactive);
    const std::uint64_t working_set = *usage > inactive ? *usage - inactive : 0;
    return *limit > working_set ? *limit - working_set : 0;
  }
  return std::nullopt;
}

}  // namespace

std::string ProcFileField(const std::string& path, const std::string& key) {
  std::ifstream in(path);
  for (std::string line; std::getline(in, line);) {
    if (line.rfind(key, 0) != 0) continue;
    const auto colon = line.find(':');
    if (colon == std::string::npos) continue;
    const auto start = line.find_first_not_of(" \t", colon + 1);
    return start == std::string::npos ? "" : line.substr(start);
  }
  return "";
}

std::uint64_t TotalMemoryBytes() { return KibField("MemTotal"); }

std::uint64_t AvailableMemoryBytes() {
  const std::uint64_t available = KibField("MemAvailable");
  const std::optional<std::uint64_t> room = CgroupRoom();
  if (!room) return available;
  return available == 0 ? *room : std::min(available, *room);
}

}  // namespace endorecon::base
