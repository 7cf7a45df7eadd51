// GPU memory and utilisation for the worker's metrics, read through NVML (the driver's management
// library), loaded at run time with dlopen so that a machine without the NVIDIA driver, or a build
// without CUDA, still runs: there the monitor is absent and says why once.
#pragma once

#include <memory>
#include <optional>
#include <string>

namespace endorecon::worker {

class GpuMonitor {
 public:
  struct Reading {
    double memory_used_bytes = 0;
    double memory_total_bytes = 0;
    double utilization = 0;  // share of the last sample period a kernel ran, 0..1
  };

  // Loads libnvidia-ml.so.1 and initialises it; nullptr, with `problem` saying why, when it cannot.
  static std::unique_ptr<GpuMonitor> Open(std::string& problem);
  ~GpuMonitor();
  GpuMonitor(const GpuMonitor&) = delete;
  GpuMonitor& operator=(const GpuMonitor&) = delete;

  // The device NVML knows by this PCI bus id ("0000:3b:00.0", as cudaDeviceProp gives it: CUDA's
  // indices follow CUDA_VISIBLE_DEVICES, NVML's do not); nullopt when NVML cannot read it.
  std::optional<Reading> Read(const std::string& pci_bus_id) const;

 private:
  struct Library;
  explicit GpuMonitor(std::unique_ptr<Library> library);
  std::unique_ptr<Library> library_;
};

}  // namespace endorecon::worker
