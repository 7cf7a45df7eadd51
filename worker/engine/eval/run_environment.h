// Where and with what results were made, as report.html states it: this machine, this build's version
// and the time now.
#pragma once

#include <nlohmann/json.hpp>

namespace endorecon::eval {

// {"machine": {"hostname", "cpu" (the model name in /proc/cpuinfo, "unknown" without one),
// "logical_cores", "memory_gib" (MemTotal of /proc/meminfo, 0 if unreadable), "os" (uname's system,
// release and machine)}, "version" (the project version and git commit of this build),
// "written" (UTC, ISO 8601, seconds)}. Never throws for what it cannot read; it says "unknown".
nlohmann::json DescribeRunEnvironment();

}  // namespace endorecon::eval
