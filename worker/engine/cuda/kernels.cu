#include <cuda_runtime.h>

#include <algorithm>
#include <cstddef>
#include <cub/warp/warp_reduce.cuh>
#include <string>

#include "common/error.h"
#include "worker/engine/base/counter_rng.h"
#include "worker/engine/cuda/device.h"
#include "worker/engine/cuda/kernels.h"
#include "worker/engine/cuda/launch.cuh"
#include "worker/engine/field/level_dispatch.h"
#include "worker/engine/render/stratified_sampler.h"

namespace endorecon::cuda {
namespace {

// --- hash grid ---

// The scatter's accumulation where neighbouring threads often add into the same place (consecutive
// samples of a ray share their grid cells at all but the finest levels): the lanes of a warp in a run
// of equal targets sum their values (CUB's head-segmented warp sum) and the run's first lane adds the
// sum atomically, one atomic a run instead of one a lane. Atomics on one address serialise in the
// cache, which is what the coarse levels' gradients cost. Every lane of the warp must make the same
// calls (a kernel's lanes past its batch add zeros somewhere valid); `storage` is the warp's
// WarpRunAdd::Storage (shared memory, one per warp of the block). The host branch exists only so the
// functor is callable from the __host__ __device__ per-sample functions.
struct WarpRunAdd {
  using Reduce = cub::WarpReduce<float>;
  using Storage = Reduce::TempStorage;
  Storage* storage = nullptr;

  __host__ __device__ void operator()(float* target, float value) const {
#ifdef __CUDA_ARCH__
    constexpr unsigned kAll = 0xffffffffu;
    const auto address = reinterpret_cast<unsigned long long>(target);
    // Every lane shuffles (a shuffle that lane 0 skipped, as `lane == 0 || shuffle` would, is undefined).
    const unsigned long long before = __shfl_up_sync(kAll, address, 1);
    const bool head = (threadIdx.x & 31u) == 0 || before != address;
    if (__all_sync(kAll, head)) {  // no two neighbours share a target: no sums to make
      atomicAdd(target, value);
      return;
    }
    const float sum = Reduce(*storage).HeadSegmentedSum(value, head);
    if (head) atomicAdd(target, sum);
#else
    *target += value;
#endif
  }
};

// A grid's levels as a kernel argument: a launch covers up to kLevelsPerLaunch levels, one per
// blockIdx.y, so the levels' blocks fill the device together.
constexpr int kLevelsPerLaunch = 32;
struct LevelSet {
  field::GridLevel level[kLevelsPerLaunch];
};

template <int F>
__global__ void HashGridForwardKernel(LevelSet levels, const float* table, const float* pos, int n,
                                      float* feat, int feat_stride) {
  const std::size_t i = ThreadIndex();
  if (i >= static_cast<std::size_t>(n)) return;
  const field::GridLevel level = levels.level[blockIdx.y];
  const float* p = pos + 3 * i;
  float* out = feat + i * feat_stride + blockIdx.y * F;
  const float* level_table = table + level.offset * F;
  if (level.dense) {
    field::GatherLevel<F, true>(level, level_table, p, out);
  } else {
    field::GatherLevel<F, false>(level, level_table, p, out);
  }
}

template <int F, bool kPosition>
__global__ void HashGridBackwardKernel(LevelSet levels, const float* pos, int n, const float* dfeat,
                                       int dfeat_stride, const float* scale, int scale_stride, float* grads,
                                       const float* table, float* dpos) {
  __shared__ WarpRunAdd::Storage storage[kThreads / 32];
  const WarpRunAdd add{&storage[threadIdx.x / 32]};
  const field::GridLevel level = levels.level[blockIdx.y];
  const std::size_t i = ThreadIndex();
  // Lanes past the batch scatter a zero gradient at the origin: every lane takes part in the sums.
  const bool live = i < static_cast<std::size_t>(n);
  const float origin[3] = {0.0f, 0.0f, 0.0f}, none[F] = {};
  const float* p = live ? pos + 3 * i : origin;
  const float* df = live ? dfeat + i * dfeat_stride + blockIdx.y * F : none;
  const float s = !live ? 0.0f : scale ? scale[i * scale_stride] : 1.0f;
  const std::size_t offset = level.offset * F;
  float d[3] = {0.0f, 0.0f, 0.0f};
  if (level.dense) {
    field::ScatterLevel<F, true, kPosition>(level, p, df, s, grads + offset,
                                            kPosition ? table + offset : nullptr, d, add);
  } else {
    field::ScatterLevel<F, false, kPosition>(level, p, df, s, grads + offset,
                                             kPosition ? table + offset : nullptr, d, add);
  }
  // Levels run side by side, so their parts of one sample's position gradient meet atomically.
  if (kPosition && live) {
    for (int a = 0; a < 3; ++a) atomicAdd(dpos + 3 * i + a, d[a]);
  }
}

// Calls launch(set, first, count) for each run of up to kLevelsPerLaunch of the grid's levels (set
// holds levels first .. first + count - 1).
template <typename Launch>
void ForLevelSets(const field::HashGrid<float>& grid, const Launch& launch) {
  for (int first = 0; first < grid.levels(); first += kLevelsPerLaunch) {
    LevelSet set{};
    const int count = std::min(kLevelsPerLaunch, grid.levels() - first);
    for (int l = 0; l < count; ++l) set.level[l] = grid.level(first + l);
    launch(set, first, count);
  }
}

// --- samplers ---

__device__ base::CounterRng<float> RayRng(const RayStreams& streams, int r) {
  return base::CounterRng<float>(streams.seed, streams.stream_base + streams.stream_step * std::uint64_t(r));
}

__global__ void StratifiedKernel(float near, float far, int n_rays, int samples, RayStreams streams, float* s,
                                 float* delta) {
  const int r = static_cast<int>(ThreadIndex());
  if (r >= n_rays) return;
  const std::size_t o = static_cast<std::size_t>(r) * samples;
  render::StratifiedSamples(near, far, samples, RayRng(streams, r), s + o, delta + o);
}

__global__ void DepthGuidedKernel(float near, float far, const float* prior_depth, int n_rays,
                                  render::DepthGuidedConfig<float> config, RayStreams streams, float* s,
                                  float* delta) {
  const int r = static_cast<int>(ThreadIndex());
  if (r >= n_rays) return;
  const std::size_t o = static_cast<std::size_t>(r) * (config.gaussian_samples + config.stratified_samples);
  render::DepthGuidedSamples(near, far, prior_depth[r], config, RayRng(streams, r), s + o, delta + o);
}

// --- volume rendering ---

__global__ void CompositeKernel(const float* sigma, const float* rgb, const float* s, const float* delta,
                                int n_rays, int samples, float min_transmittance, float* weights,
                                render::RayComposite<float>* out) {
  const int r = static_cast<int>(ThreadIndex());
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
  const int r = static_cast<int>(ThreadIndex());
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
  const int r = static_cast<int>(ThreadIndex());
  if (r >= n_rays) return;
  const std::size_t o = static_cast<std::size_t>(r) * samples;
  loss[r] = train::RayLoss(rays[r], weights + o, mean_rgb + 3 * o, log_var + o, samples,
                           target_rgb + 3 * static_cast<std::size_t>(r), prior_depth ? prior_depth[r] : 0.0f,
                           terms, &grad[r], d_mean_rgb ? d_mean_rgb + 3 * o : nullptr,
                           d_log_var ? d_log_var + o : nullptr);
}

}  // namespace

void HashGridForward(const field::HashGrid<float>& grid, const float* table, const float* pos, int n,
                     float* feat, int feat_stride) {
  if (n <= 0) return;
  field::DispatchFeatures(grid.features(), [&](auto fc) {
    constexpr int F = decltype(fc)::value;
    ForLevelSets(grid, [&](const LevelSet& set, int first, int count) {
      const dim3 blocks(Blocks(n), static_cast<unsigned>(count));
      HashGridForwardKernel<F><<<blocks, kThreads>>>(set, table, pos, n, feat + first * F, feat_stride);
      CheckLaunch("hash grid forward kernel");
    });
  });
}

void HashGridBackward(const field::HashGrid<float>& grid, const float* pos, int n, const float* dfeat,
                      int dfeat_stride, const float* scale, int scale_stride, float* grads,
                      const float* table, float* dpos_add) {
  if (dpos_add != nullptr && table == nullptr)
    FailInvalid("hash grid backward: a position gradient needs the grid's table");
  if (n <= 0) return;
  field::DispatchFeatures(grid.features(), [&](auto fc) {
    constexpr int F = decltype(fc)::value;
    ForLevelSets(grid, [&](const LevelSet& set, int first, int count) {
      const dim3 blocks(Blocks(n), static_cast<unsigned>(count));
      const float* df = dfeat + first * F;
      if (dpos_add) {
        HashGridBackwardKernel<F, true><<<blocks, kThreads>>>(set, pos, n, df, dfeat_stride, scale,
                                                              scale_stride, grads, table, dpos_add);
      } else {
        HashGridBackwardKernel<F, false><<<blocks, kThreads>>>(set, pos, n, df, dfeat_stride, scale,
                                                               scale_stride, grads, table, dpos_add);
      }
      CheckLaunch("hash grid backward kernel");
    });
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
