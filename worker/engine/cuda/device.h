// NVIDIA GPUs as the host code sees them: which devices there are, and device memory. A plain C++
// header (no CUDA types), so code compiled by the host compiler can include it; the functions are
// defined in device.cu and exist only in builds with ENDORECON_WITH_CUDA.
//
// Errors: a failed CUDA call throws endorecon::Error on the host side, with the CUDA error's name
// and what was being done (kResourceExhausted for out-of-memory, kUnavailable when there is no
// usable device or driver, kInternal otherwise). Nothing throws inside a kernel; a kernel's own
// failure surfaces at the next checked call (Synchronize, a copy).
#pragma once

#include <cstddef>
#include <string>
#include <utility>
#include <vector>

#include "common/error.h"

namespace endorecon::cuda {

struct DeviceInfo {
  int index = 0;     // as cudaSetDevice takes it (after CUDA_VISIBLE_DEVICES)
  std::string name;  // e.g. "Tesla V100-SXM2-32GB"
  int compute_major = 0, compute_minor = 0;
  int multiprocessors = 0;
  std::size_t total_memory_bytes = 0;
  std::string pci_bus_id;  // "0000:3b:00.0": how NVML and nvidia-smi name the same device
};

// What ListDevices found: the devices, or none and why (no driver, no device, driver too old).
// Never throws: a machine without a GPU is a normal answer, not an error. Reads properties only,
// so it creates no context (and takes no memory) on devices other workers may be using.
struct DeviceList {
  std::vector<DeviceInfo> devices;
  std::string problem;  // empty when the query itself worked (even with zero devices)
};

DeviceList ListDevices();

// How logs and metrics.json name device `index`: "cuda:0 (NVIDIA H200)". Throws std::out_of_range for
// an index ListDevices does not list.
std::string DeviceName(int index);

// Number of usable devices; 0 when there is no driver or no device (never throws).
int DeviceCount();

// Makes `index` the current device of the calling thread. Throws Error(kInvalidArgument) for an
// index outside [0, DeviceCount()).
void SetDevice(int index);

// Free memory of the current device, in bytes (creates its context if there is none yet).
std::size_t FreeMemoryBytes();

// Waits for all work on the current device; throws if a kernel failed.
void Synchronize();

// Throws the Error described above when `status` (a cudaError_t) is not cudaSuccess; `what` says
// what was being done ("cudaMalloc of 64 MiB", "hash level forward kernel").
void CheckStatus(int status, const char* what);

// Raw device memory; Free(nullptr) does nothing. Copies are synchronous.
void* DeviceAlloc(std::size_t bytes);
void DeviceFree(void* ptr) noexcept;
void CopyToDevice(void* device_dst, const void* host_src, std::size_t bytes);
void CopyToHost(void* host_dst, const void* device_src, std::size_t bytes);
void ZeroDevice(void* device_dst, std::size_t bytes);

// An owning array of n trivially copyable T in device memory (move-only).
template <typename T>
class DeviceArray {
 public:
  DeviceArray() = default;
  explicit DeviceArray(std::size_t n) : data_(static_cast<T*>(DeviceAlloc(n * sizeof(T)))), size_(n) {}
  explicit DeviceArray(const std::vector<T>& host) : DeviceArray(host.size()) { Upload(host); }
  DeviceArray(DeviceArray&& other) noexcept
      : data_(std::exchange(other.data_, nullptr)), size_(std::exchange(other.size_, 0)) {}
  DeviceArray& operator=(DeviceArray&& other) noexcept {
    std::swap(data_, other.data_);
    std::swap(size_, other.size_);
    return *this;
  }
  DeviceArray(const DeviceArray&) = delete;
  DeviceArray& operator=(const DeviceArray&) = delete;
  ~DeviceArray() { DeviceFree(data_); }

  T* data() { return data_; }
  const T* data() const { return data_; }
  std::size_t size() const { return size_; }

  // Throws Error(kInvalidArgument) unless host.size() == size().
  void Upload(const std::vector<T>& host) { CopyToDevice(data_, host.data(), Bytes(host.size())); }
  std::vector<T> Download() const {
    std::vector<T> host(size_);
    CopyToHost(host.data(), data_, Bytes(size_));
    return host;
  }
  void Zero() { ZeroDevice(data_, Bytes(size_)); }

 private:
  std::size_t Bytes(std::size_t n) const {
    if (n != size_) {
      FailInvalid("device array of " + std::to_string(size_) + " elements given a host array of " +
                  std::to_string(n));
    }
    return n * sizeof(T);
  }

  T* data_ = nullptr;
  std::size_t size_ = 0;
};

}  // namespace endorecon::cuda
