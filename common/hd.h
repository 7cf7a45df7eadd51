// ENDORECON_HD marks per-sample and per-ray math that both the CPU backend and CUDA kernels call.
// Such functions take plain pointers and scalars: no heap, no exceptions, no STL containers.
#pragma once

#if defined(__CUDACC__)
#define ENDORECON_HD __host__ __device__ inline
#else
#define ENDORECON_HD inline
#endif
