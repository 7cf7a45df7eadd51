#include "worker/runtime/device_list.h"

#include <algorithm>
#include <sstream>

#include "common/error.h"

namespace endorecon::worker {
namespace {

bool AllDigits(const std::string& s) {
  return !s.empty() && s.find_first_not_of("0123456789") == std::string::npos;
}

}  // namespace

std::vector<Device> ParseDevices(const std::string& spec, int threads, int cores) {
  std::vector<Device> devices;
  if (spec == "cpu" || spec.rfind("cpu:", 0) == 0) {
    const std::string count = spec == "cpu" ? "1" : spec.substr(4);
    if (!AllDigits(count) || count.size() > 4 || std::stoi(count) < 1) {
      FailInvalid("--devices " + spec + ": expected cpu:N with N a number of slots >= 1");
    }
    for (int i = 0; i < std::stoi(count); ++i) devices.push_back({"cpu" + std::to_string(i), "cpu", 0});
  } else {
    std::stringstream list(spec);
    std::string index;
    while (std::getline(list, index, ',')) {
      if (!AllDigits(index) || index.size() > 4) {
        FailInvalid("--devices " + spec + ": expected cpu, cpu:N or GPU indices like 0,1");
      }
      devices.push_back({"gpu" + index, "cuda", 0, std::stoi(index)});
    }
    if (devices.empty()) FailInvalid("--devices " + spec + ": expected cpu, cpu:N or GPU indices like 0,1");
  }
  for (auto& device : devices)
    device.threads = threads > 0 ? threads : std::max(1, std::max(1, cores) / int(devices.size()));
  return devices;
}

void DescribeDevices(std::vector<Device>& devices) {
  for (auto& device : devices) device.description = DescribeDevice(device.EngineDevice());
}

}  // namespace endorecon::worker
