// What memory this machine has, as /proc and the process's cgroup (a container's limit) say it: the
// run's memory check (scene/load_options.h memory_bytes) and report.html's machine description.
#pragma once

#include <cstdint>
#include <string>

namespace endorecon::base {

// The value after "key<spaces>:" on the first line of `path` starting with `key` ("" if none, or the
// file is unreadable): /proc/meminfo's and /proc/cpuinfo's lines.
std::string ProcFileField(const std::string& path, const std::string& key);

// MemTotal, in bytes; 0 if unreadable.
std::uint64_t TotalMemoryBytes();

// The memory a new allocation may take: MemAvailable, and within a cgroup memory limit (v2
// memory.max, v1 memory.limit_in_bytes) at most the limit less the cgroup's working set (its usage
// less the page cache it may drop: inactive_file, as the kubelet counts it). 0 if unreadable.
std::uint64_t AvailableMemoryBytes();

}  // namespace endorecon::base
