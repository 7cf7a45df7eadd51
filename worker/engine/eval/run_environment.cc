#include "worker/engine/eval/run_environment.h"

#include <fmt/chrono.h>
#include <fmt/format.h>
#include <sys/utsname.h>
#include <unistd.h>

#include <ctime>
#include <fstream>
#include <string>
#include <thread>

#include "endorecon_version.h"

namespace endorecon::eval {
namespace {

// The value after "key<spaces>:" on the first line of `path` that starts with `key`, or "".
std::string ProcField(const char* path, const std::string& key) {
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

}  // namespace

nlohmann::json DescribeRunEnvironment() {
  char host[256] = {};
  if (gethostname(host, sizeof host - 1) != 0) host[0] = '\0';
  std::string cpu = ProcField("/proc/cpuinfo", "model name");
  double memory_gib = 0;
  try {
    // "MemTotal:  131862252 kB"
    memory_gib = std::stod(ProcField("/proc/meminfo", "MemTotal")) / (1024.0 * 1024.0);
  } catch (const std::exception&) {
    memory_gib = 0;
  }
  utsname names{};
  const std::string os =
      uname(&names) == 0 ? fmt::format("{} {} {}", names.sysname, names.release, names.machine) : "unknown";
  return {{"machine",
           {{"hostname", host[0] ? host : "unknown"},
            {"cpu", cpu.empty() ? "unknown" : cpu},
            {"logical_cores", std::thread::hardware_concurrency()},
            {"memory_gib", memory_gib},
            {"os", os}}},
          {"version", ENDORECON_VERSION},
          {"written", fmt::format("{:%Y-%m-%dT%H:%M:%SZ}", fmt::gmtime(std::time(nullptr)))}};
}

}  // namespace endorecon::eval
