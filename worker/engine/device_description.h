// What a device the engine runs on is, for people and for the worker's metrics: "cpu" or "cuda:N"
// (N a CUDA device index, as CUDA_VISIBLE_DEVICES leaves them), as --device takes them.
#pragma once

#include <cstdint>
#include <string>

namespace endorecon {

struct DeviceDescription {
  std::string device;             // "cpu" or "cuda:N"
  std::string kind;               // "cpu" or "cuda"
  int cuda_index = -1;            // N of "cuda:N"
  std::string model;              // the CPU's model name, or the GPU's name and compute capability
  std::int64_t memory_bytes = 0;  // the machine's memory, or the GPU's
  std::string pci_bus_id;         // a GPU's, as NVML names it ("0000:3b:00.0")
};

// Throws Error(kInvalidArgument) naming the device and why when this build or machine cannot run
// it: another form, a build without CUDA, no such CUDA device (with the devices there are).
DeviceDescription DescribeDevice(const std::string& device);

}  // namespace endorecon
