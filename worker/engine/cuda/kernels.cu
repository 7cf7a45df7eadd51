#include <cuda_runtime.h>

#include <cstddef>
#include <string>

#include "common/error.h"
#include "worker/engine/base/counter_rng.h"
#include "worker/engine/cuda/device.h"
#include "worker/engine/cuda/kernels.h"
#include "worker/engine/field/level_dispatch.h"
#include "worker/engine/render/stratified_sampler.h"

namespace endorecon::cuda {
namespace {

constexpr int kThreads = 128;

int Blocks(int n) { return (n + kThreads - 1) / kThreads; }

void CheckLaunch(const char* kernel) { CheckStatus(cudaGetLastError(), kernel); }

__device__ int ThreadIndex() { return static_cast<int>(blockIdx.x * blockDim.x + threadIdx.x); }

// --- hash grid ---

// The scatter's accumulation when many threads add into one table: atomic on the device. (The host
// branch exists only so the functor is callable from field::ScatterLevel's __host__ __device__ body.)
struct AtomicAdd {
  __host__ __device__ void operator()(float* target, float value) const {
#ifdef __CUDA_ARCH__
    atomicAdd(target, value);
#else
    *target += value;
#endif
  }
};

template <int F, bool kDense>
__global__ void HashLevelForwardKernel(field::GridLevel level, const float* table, const float* pos, int n,
                                       float* feat, int feat_stride) {
  const int i = ThreadIndex();
  if (i >= n) return;
  field::GatherLevel<F, kDense>(level, table, pos + 3 * static_cast<std::size_t>(i),
                                feat + static_cast<std::size_t>(i) * feat_stride);
}

template <int F, bool kDense, bool kPosition>
__global__ void HashLevelBackwardKernel(field::GridLevel level, const float* pos, int n, const float* dfeat,
                                        int dfeat_stride, const float* scale, float* grads,
                                        const float* table, float* dpos) {
  const int i = ThreadIndex();
  if (i >= n) return;
  const std::size_t r = static_cast<std::size_t>(i);
  field::ScatterLevel<F, kDense, kPosition>(level, pos + 3 * r, dfeat + r * dfeat_stride,
                                            scale ? scale[r] : 1.0f, grads, table,
                                            kPosition ? dpos + 3 * r : nullptr, AtomicAdd{});
}

// --- samplers ---

__device__ base::CounterRng<float> RayRng(const RayStreams& streams, int r) {
  return base::CounterRng<float>(streams.seed, streams.stream_base + streams.stream_step * std::uint64_t(r));
}

__global__ void StratifiedKernel(float near, float far, int n_rays, int samples, RayStreams streams, float* s,
                                 float* delta) {
  const int r = ThreadIndex();
  if (r >= n_rays) return;
  const std::size_t o = static_cast<std::size_t>(r) * samples;
  render::StratifiedSamples(near, far, samples, RayRng(streams, r), s + o, delta + o);
}

__global__ void DepthGuidedKernel(float near, float far, const float* prior_depth, int n_rays,
                                  render::DepthGuidedConfig<float> config, RayStreams streams, float* s,
                                  float* delta) {
  const int r = ThreadIndex();
  if (r >= n_rays) return;
  const std::size_t o = static_cast<std::size_t>(r) * (config.gaussian_samples + config.stratified_samples);
  render::DepthGuidedSamples(near, far, prior_depth[r], config, RayRng(streams, r), s + o, delta + o);
}

// --- volume rendering ---

__global__ void CompositeKernel(const float* sigma, const float* rgb, const float* s, const float* delta,
                                int n_rays, int samples, float min_transmittance, float* weights,
                                render::RayComposite<float>* out) {
  const int r = ThreadIndex();
  if (r >= n_rays) return;
  const std::size_t o = static_cast<std::size_t>(r) * samples;
  out[r] =
      render::CompositeRay(sigma + o, rgb + 3 * o, s + o, delta + o, samples, weights + o, min_transmittance);
}

__global__ void CompositeBackwardKernel(const float* sigma, const float* rgb, const float* s,
                                        const float* delta, const float* weights, int n_rays, int samples,
                                        const render::RayComposite<float>* forward,
                                        const render::RayCompositeGrad<float>* grad, const float* d_weights,
                                        float* d_sigma, float* d_rgb) {
  const int r = ThreadIndex();
  if (r >= n_rays) return;
  const std::size_t o = static_cast<std::size_t>(r) * samples;
  render::CompositeRayBackward(sigma + o, rgb + 3 * o, s + o, delta + o, weights + o, forward[r], grad[r],
                               d_weights ? d_weights + o : nullptr, d_sigma + o, d_rgb + 3 * o);
}

// --- losses ---

__global__ void RayLossKernel(const render::RayComposite<float>* rays, const float* weights,
                              const float* mean_rgb, const float* log_var, const float* target_rgb,
                              const float* prior_depth, int n_rays, int samples, train::RayLossTerms terms,
                              float* loss, render::RayCompositeGrad<float>* grad, float* d_mean_rgb,
                              float* d_log_var) {
  const int r = ThreadIndex();
  if (r >= n_rays) return;
  const std::size_t o = static_cast<std::size_t>(r) * samples;
  loss[r] = train::RayLoss(rays[r], weights + o, mean_rgb + 3 * o, log_var + o, samples,
                           target_rgb + 3 * static_cast<std::size_t>(r), prior_depth ? prior_depth[r] : 0.0f,
                           terms, &grad[r], d_mean_rgb ? d_mean_rgb + 3 * o : nullptr,
                           d_log_var ? d_log_var + o : nullptr);
}

}  // namespace

void HashLevelForward(const field::GridLevel& level, int features, const float* table, const float* pos,
                      int n, float* feat, int feat_stride) {
  field::DispatchLevel(features, level, [&](auto fc, auto dense) {
    constexpr int F = decltype(fc)::value;
    constexpr bool kDense = decltype(dense)::value;
    if (n <= 0) return;
    HashLevelForwardKernel<F, kDense><<<Blocks(n), kThreads>>>(level, table, pos, n, feat, feat_stride);
    CheckLaunch("hash level forward kernel");
  });
}

void HashLevelBackward(const field::GridLevel& level, int features, const float* pos, int n,
                       const float* dfeat, int dfeat_stride, const float* scale, float* grads,
                       const float* table, float* dpos_add) {
  if (dpos_add != nullptr && table == nullptr)
    FailInvalid("hash level backward: a position gradient needs the level's table");
  field::DispatchLevel(features, level, [&](auto fc, auto dense) {
    constexpr int F = decltype(fc)::value;
    constexpr bool kDense = decltype(dense)::value;
    if (n <= 0) return;
    if (dpos_add) {
      HashLevelBackwardKernel<F, kDense, true>
          <<<Blocks(n), kThreads>>>(level, pos, n, dfeat, dfeat_stride, scale, grads, table, dpos_add);
    } else {
      HashLevelBackwardKernel<F, kDense, false>
          <<<Blocks(n), kThreads>>>(level, pos, n, dfeat, dfeat_stride, scale, grads, table, dpos_add);
    }
    CheckLaunch("hash level backward kernel");
  });
}

void StratifiedSampleRays(float near, float far, int n_rays, int samples, const RayStreams& streams, float* s,
                          float* delta) {
  if (n_rays <= 0) return;
  StratifiedKernel<<<Blocks(n_rays), kThreads>>>(near, far, n_rays, samples, streams, s, delta);
  CheckLaunch("stratified sampler kernel");
}

void DepthGuidedSampleRays(float near, float far, const float* prior_depth, int n_rays,
                           const render::DepthGuidedConfig<float>& config, const RayStreams& streams,
                           float* s, float* delta) {
  if (n_rays <= 0) return;
  DepthGuidedKernel<<<Blocks(n_rays), kThreads>>>(near, far, prior_depth, n_rays, config, streams, s, delta);
  CheckLaunch("depth-guided sampler kernel");
}

void CompositeRays(const float* sigma, const float* rgb, const float* s, const float* delta, int n_rays,
                   int samples, float min_transmittance, float* weights, render::RayComposite<float>* out) {
  if (n_rays <= 0) return;
  CompositeKernel<<<Blocks(n_rays), kThreads>>>(sigma, rgb, s, delta, n_rays, samples, min_transmittance,
                                                weights, out);
  CheckLaunch("composite kernel");
}

void CompositeRaysBackward(const float* sigma, const float* rgb, const float* s, const float* delta,
                           const float* weights, int n_rays, int samples,
                           const render::RayComposite<float>* forward,
                           const render::RayCompositeGrad<float>* grad, const float* d_weights,
                           float* d_sigma, float* d_rgb) {
  if (n_rays <= 0) return;
  CompositeBackwardKernel<<<Blocks(n_rays), kThreads>>>(sigma, rgb, s, delta, weights, n_rays, samples,
                                                        forward, grad, d_weights, d_sigma, d_rgb);
  CheckLaunch("composite backward kernel");
}

void RayLosses(const render::RayComposite<float>* rays, const float* weights, const float* mean_rgb,
               const float* log_var, const float* target_rgb, const float* prior_depth, int n_rays,
               int samples, const train::RayLossTerms& terms, float* loss,
               render::RayCompositeGrad<float>* grad, float* d_mean_rgb, float* d_log_var) {
  if (terms.depth_scale != 0.0f && prior_depth == nullptr)
    FailInvalid("ray losses: a depth term (depth_scale " + std::to_string(terms.depth_scale) +
                ") needs prior depths");
  if (n_rays <= 0) return;
  RayLossKernel<<<Blocks(n_rays), kThreads>>>(rays, weights, mean_rgb, log_var, target_rgb, prior_depth,
                                              n_rays, samples, terms, loss, grad, d_mean_rgb, d_log_var);
  CheckLaunch("ray loss kernel");
}

}  // namespace endorecon::cuda
