#include "worker/engine/device_description.h"

#include <unistd.h>

#include <fstream>

#include "common/error.h"
#ifdef ENDORECON_WITH_CUDA
#include "worker/engine/cuda/device.h"
#endif

namespace endorecon {
namespace {

// /proc/cpuinfo's first "model name" (x86; other machines may have none: then "CPU").
std::string CpuModel() {
  std::ifstream cpuinfo("/proc/cpuinfo");
  std::string line;
  while (std::getline(cpuinfo, line)) {
    if (line.rfind("model name", 0) != 0) continue;
    const auto colon = line.find(':');
    if (colon != std::string::npos && colon + 2 <= line.size()) return line.substr(colon + 2);
  }
  return "CPU";
}

}  // namespace

DeviceDescription DescribeDevice(const std::string& device) {
  DeviceDescription d;
  d.device = device;
  if (device == "cpu") {
    d.kind = "cpu";
    d.model = CpuModel();
    d.memory_bytes = static_cast<std::int64_t>(sysconf(_SC_PHYS_PAGES)) * sysconf(_SC_PAGESIZE);
    return d;
  }
  const std::string prefix = "cuda:";
  const std::string number = device.rfind(prefix, 0) == 0 ? device.substr(prefix.size()) : "";
  if (number.empty() || number.size() > 3 || number.find_first_not_of("0123456789") != std::string::npos) {
    FailInvalid("device '" + device + "': expected cpu or cuda:N (N a CUDA device index)");
  }
  d.kind = "cuda";
  d.cuda_index = std::stoi(number);
#ifdef ENDORECON_WITH_CUDA
  const cuda::DeviceList list = cuda::ListDevices();
  if (d.cuda_index >= static_cast<int>(list.devices.size())) {
    FailInvalid("device " + device + ": no such CUDA device (" +
                (list.problem.empty() ? std::to_string(list.devices.size()) + " found" : list.problem) + ")");
  }
  const cuda::DeviceInfo& info = list.devices[d.cuda_index];
  d.model = info.name + ", sm_" + std::to_string(info.compute_major) + std::to_string(info.compute_minor);
  d.memory_bytes = static_cast<std::int64_t>(info.total_memory_bytes);
  d.pci_bus_id = info.pci_bus_id;
  return d;
#else
  FailInvalid("device " + device + ": this build has no CUDA engine (it was built without a CUDA toolkit)");
#endif
}

}  // namespace endorecon
