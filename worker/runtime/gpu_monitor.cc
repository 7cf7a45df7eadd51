#include "worker/runtime/gpu_monitor.h"

#include <dlfcn.h>

namespace endorecon::worker {
namespace {

// NVML's C ABI (nvml.h, stable across driver releases), declared here because the header comes
// only with the CUDA toolkit and the CPU-only build must compile this file too.
using NvmlReturn = int;  // nvmlReturn_t; 0 is NVML_SUCCESS
using NvmlDevice = struct NvmlDeviceOpaque*;
struct NvmlMemory {
  unsigned long long total, free, used;
};
struct NvmlUtilization {
  unsigned int gpu, memory;  // percent
};

}  // namespace

struct GpuMonitor::Library {
  void* handle = nullptr;
  NvmlReturn (*init)() = nullptr;
  NvmlReturn (*shutdown)() = nullptr;
  NvmlReturn (*by_bus_id)(const char*, NvmlDevice*) = nullptr;
  NvmlReturn (*memory)(NvmlDevice, NvmlMemory*) = nullptr;
  NvmlReturn (*utilization)(NvmlDevice, NvmlUtilization*) = nullptr;
};

std::unique_ptr<GpuMonitor> GpuMonitor::Open(std::string& problem) {
  auto library = std::make_unique<Library>();
  library->handle = dlopen("libnvidia-ml.so.1", RTLD_NOW | RTLD_LOCAL);
  if (library->handle == nullptr) {
    const char* error = dlerror();
    problem = std::string("cannot load NVML (libnvidia-ml.so.1, part of the NVIDIA driver): ") +
              (error ? error : "unknown reason");
    return nullptr;
  }
  const auto symbol = [&](const char* name) { return dlsym(library->handle, name); };
  library->init = reinterpret_cast<NvmlReturn (*)()>(symbol("nvmlInit_v2"));
  library->shutdown = reinterpret_cast<NvmlReturn (*)()>(symbol("nvmlShutdown"));
  library->by_bus_id =
      reinterpret_cast<NvmlReturn (*)(const char*, NvmlDevice*)>(symbol("nvmlDeviceGetHandleByPciBusId_v2"));
  library->memory =
      reinterpret_cast<NvmlReturn (*)(NvmlDevice, NvmlMemory*)>(symbol("nvmlDeviceGetMemoryInfo"));
  library->utilization =
      reinterpret_cast<NvmlReturn (*)(NvmlDevice, NvmlUtilization*)>(symbol("nvmlDeviceGetUtilizationRates"));
  if (!library->init || !library->shutdown || !library->by_bus_id || !library->memory ||
      !library->utilization) {
    problem = "libnvidia-ml.so.1 lacks the NVML calls the worker reads (a driver older than NVML 10?)";
    dlclose(library->handle);
    return nullptr;
  }
  if (const NvmlReturn status = library->init(); status != 0) {
    problem =
        "nvmlInit_v2 failed with NVML error " + std::to_string(status) + " (no driver loaded, or no GPU)";
    dlclose(library->handle);
    return nullptr;
  }
  return std::unique_ptr<GpuMonitor>(new GpuMonitor(std::move(library)));
}

GpuMonitor::GpuMonitor(std::unique_ptr<Library> library) : library_(std::move(library)) {}

GpuMonitor::~GpuMonitor() {
  library_->shutdown();
  dlclose(library_->handle);
}

std::optional<GpuMonitor::Reading> GpuMonitor::Read(const std::string& pci_bus_id) const {
  NvmlDevice device = nullptr;
  if (library_->by_bus_id(pci_bus_id.c_str(), &device) != 0) return std::nullopt;
  NvmlMemory memory{};
  NvmlUtilization utilization{};
  if (library_->memory(device, &memory) != 0 || library_->utilization(device, &utilization) != 0) {
    return std::nullopt;
  }
  return Reading{static_cast<double>(memory.used), static_cast<double>(memory.total),
                 utilization.gpu / 100.0};
}

}  // namespace endorecon::worker
