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

// Launches of at most this many threads (the per-ray kernels: a step's 1,024 rays, whose threads each
// walk a ray's samples) go in blocks of one warp, so they spread over 32 SMs rather than 8.
inline constexpr std::size_t kSmallLaunch = 16384;

template <typename Fn>
void ForEach(std::size_t n, const Fn& fn, const char* what) {
  if (n == 0) return;
  const unsigned threads = n <= kSmallLaunch ? 32u : static_cast<unsigned>(kThreads);
  ForEachKernel<<<static_cast<unsigned>((n + threads - 1) / threads), threads>>>(n, fn);
  CheckLaunch(what);
}

}  // namespace endorecon::cuda
