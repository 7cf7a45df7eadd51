#include <cuda_runtime.h>

#include <cstdio>
#include <string>

#include "common/error.h"
#include "worker/engine/cuda/device.h"

namespace endorecon::cuda {
namespace {

ErrorCode CodeFor(cudaError_t status) {
  switch (status) {
    case cudaErrorMemoryAllocation:
      return ErrorCode::kResourceExhausted;
    case cudaErrorNoDevice:
    case cudaErrorInsufficientDriver:
    case cudaErrorInvalidDevice:
      return ErrorCode::kUnavailable;
    case cudaErrorInvalidValue:
      return ErrorCode::kInvalidArgument;
    default:
      return ErrorCode::kInternal;
  }
}

std::string Describe(cudaError_t status) {
  return std::string(cudaGetErrorName(status)) + " (" + cudaGetErrorString(status) + ")";
}

std::string MiB(std::size_t bytes) { return std::to_string(bytes >> 20) + " MiB"; }

}  // namespace

void CheckStatus(int status, const char* what) {
  const auto error = static_cast<cudaError_t>(status);
  if (error == cudaSuccess) return;
  // Reset the thread's last error (for errors that are not sticky) so no later check reports it again.
  cudaGetLastError();
  Fail(CodeFor(error), std::string("CUDA: ") + what + " failed: " + Describe(error));
}

DeviceList ListDevices() {
  DeviceList list;
  int count = 0;
  const cudaError_t status = cudaGetDeviceCount(&count);
  if (status != cudaSuccess) {
    cudaGetLastError();
    list.problem = "cudaGetDeviceCount: " + Describe(status);
    return list;
  }
  for (int i = 0; i < count; ++i) {
    cudaDeviceProp prop{};
    const cudaError_t prop_status = cudaGetDeviceProperties(&prop, i);
    if (prop_status != cudaSuccess) {
      cudaGetLastError();
      list.problem = "cudaGetDeviceProperties(" + std::to_string(i) + "): " + Describe(prop_status);
      continue;
    }
    DeviceInfo info;
    info.index = i;
    info.name = prop.name;
    info.compute_major = prop.major;
    info.compute_minor = prop.minor;
    info.multiprocessors = prop.multiProcessorCount;
    info.total_memory_bytes = prop.totalGlobalMem;
    char bus_id[32] = {};
    std::snprintf(bus_id, sizeof bus_id, "%04x:%02x:%02x.0", prop.pciDomainID, prop.pciBusID, prop.pciDeviceID);
    info.pci_bus_id = bus_id;
    list.devices.push_back(info);
  }
  return list;
}

std::string DeviceName(int index) {
  return "cuda:" + std::to_string(index) + " (" +
         ListDevices().devices.at(static_cast<std::size_t>(index)).name + ")";
}

int DeviceCount() {
  int count = 0;
  if (cudaGetDeviceCount(&count) != cudaSuccess) {
    cudaGetLastError();
    return 0;
  }
  return count;
}

void SetDevice(int index) {
  const int count = DeviceCount();
  if (index < 0 || index >= count) {
    FailInvalid("CUDA device " + std::to_string(index) + " does not exist (" + std::to_string(count) +
                " device(s) visible)");
  }
  CheckStatus(cudaSetDevice(index), ("cudaSetDevice(" + std::to_string(index) + ")").c_str());
}

std::size_t FreeMemoryBytes() {
  std::size_t free_bytes = 0, total_bytes = 0;
  CheckStatus(cudaMemGetInfo(&free_bytes, &total_bytes), "cudaMemGetInfo");
  return free_bytes;
}

void Synchronize() { CheckStatus(cudaDeviceSynchronize(), "cudaDeviceSynchronize (a kernel failed)"); }

void* DeviceAlloc(std::size_t bytes) {
  void* ptr = nullptr;
  if (bytes == 0) return nullptr;
  CheckStatus(cudaMalloc(&ptr, bytes), ("cudaMalloc of " + MiB(bytes)).c_str());
  return ptr;
}

void DeviceFree(void* ptr) noexcept {
  if (ptr != nullptr) cudaFree(ptr);
}

void CopyToDevice(void* device_dst, const void* host_src, std::size_t bytes) {
  if (bytes == 0) return;
  CheckStatus(cudaMemcpy(device_dst, host_src, bytes, cudaMemcpyHostToDevice), "copy to device");
}

void CopyToHost(void* host_dst, const void* device_src, std::size_t bytes) {
  if (bytes == 0) return;
  CheckStatus(cudaMemcpy(host_dst, device_src, bytes, cudaMemcpyDeviceToHost), "copy to host");
}

void ZeroDevice(void* device_dst, std::size_t bytes) {
  if (bytes == 0) return;
  CheckStatus(cudaMemset(device_dst, 0, bytes), "cudaMemset");
}

}  // namespace endorecon::cuda
