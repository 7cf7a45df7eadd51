#include "worker/engine/device_description.h"

#include "common/error.h"
#include "worker/engine/eval/run_environment.h"
#ifdef ENDORECON_WITH_CUDA
#include "worker/engine/cuda/device.h"
#endif

namespace endorecon {

DeviceDescription DescribeDevice(const std::string& device) {
  DeviceDescription d;
  d.device = device;
  if (device == "cpu") {
    d.kind = "cpu";
    const nlohmann::json machine = eval::DescribeRunEnvironment().at("machine");
    d.model = machine.at("cpu").get<std::string>();
    d.memory_bytes = static_cast<std::int64_t>(machine.at("memory_gib").get<double>() * (1 << 30));
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
