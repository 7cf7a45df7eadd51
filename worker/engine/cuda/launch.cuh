// What every kernel file shares: the launch shape of one-thread-per-element kernels, the launch check
// and the atomic accumulation the scatters use. Included by .cu files only.
#pragma once

#include <cuda_runtime.h>

#include <cstddef>

#include "worker/engine/cuda/device.h"

namespace endorecon::cuda {

inline constexpr int kThreads = 128;

inline unsigned Blocks(std::size_t n) { return static_cast<unsigned>((n + kThreads - 1) / kThreads); }

inline void CheckLaunch(const char* kernel) { CheckStatus(cudaGetLastError(), kernel); }

__device__ inline std::size_t ThreadIndex() {
  return static_cast<std::size_t>(blockIdx.x) * blockDim.x + threadIdx.x;
}

// The scatter's accumulation when many threads add into one table: atomic on the device. (The host
// branch exists only so the functor is callable from the __host__ __device__ per-sample functions.)
struct AtomicAdd {
  __host__ __device__ void operator()(float* target, float value) const {
#ifdef __CUDA_ARCH__
    atomicAdd(target, value);
#else
    *target += value;
#endif
  }
};

// Calls fn(i) for i in [0, n) on the device, one thread each.
template <typename Fn>
__global__ void ForEachKernel(std::size_t n, Fn fn) {
  const std::size_t i = ThreadIndex();
  if (i < n) fn(i);
}

template <typename Fn>
void ForEach(std::size_t n, const Fn& fn, const char* what) {
  if (n == 0) return;
  ForEachKernel<<<Blocks(n), kThreads>>>(n, fn);
  CheckLaunch(what);
}

}  // namespace endorecon::cuda
