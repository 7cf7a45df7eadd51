#include "worker/engine/eval/run_environment.h"

#include <fmt/chrono.h>
#include <fmt/format.h>
#include <sys/utsname.h>
#include <unistd.h>

#include <ctime>
#include <string>
#include <thread>

#include "endorecon_version.h"
#include "worker/engine/base/machine_memory.h"

namespace endorecon::eval {

nlohmann::json DescribeRunEnvironment() {
  char host[256] = {};
  if (gethostname(host, sizeof host - 1) != 0) host[0] = '\0';
  const std::string cpu = base::ProcFileField("/proc/cpuinfo", "model name");
  const double memory_gib = double(base::TotalMemoryBytes()) / double(1 << 30);
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
