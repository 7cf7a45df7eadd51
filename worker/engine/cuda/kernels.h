// The engine's per-sample and per-ray math on NVIDIA GPUs: thin kernels around the same ENDORECON_HD
// functions the CPU loops call (field/hash_math.h, render/*_sampler.h, render/volume_renderer.h,
// train/losses.h), so the CPU tests vouch for the GPU path too. A plain C++ header (no CUDA types);
// defined in kernels.cu, present only in builds with ENDORECON_WITH_CUDA.
//
// Every pointer is DEVICE memory (cuda::DeviceArray or cuda::DeviceAlloc), float, laid out exactly as
// the CPU code lays it out. Launches go to the current device's default stream and return at once;
// a launch error throws endorecon::Error (device.h), an error inside a kernel surfaces at the next
// Synchronize or copy. Ray batches have a fixed number of samples per ray, as the trainer's: sample j
// of ray r is element r * samples + j (colours 3 floats each).
#pragma once

#include <cstdint>

#include "worker/engine/field/hash_grid.h"
#include "worker/engine/render/depth_guided_sampler.h"
#include "worker/engine/render/volume_renderer.h"
#include "worker/engine/train/ray_loss.h"

namespace endorecon::cuda {

// --- hash grid: every level of one grid in one launch (field::HashGrid's layout) ---

// feat[i * feat_stride + l * features + f] = trilinear blend of level l's table at pos[3i..3i+2], for
// every level l of `grid` and f < features; `table` is the grid's whole table (level l from
// level(l).offset * features on).
void HashGridForward(const field::HashGrid<float>& grid, const float* table, const float* pos, int n,
                     float* feat, int feat_stride);

// grads[level l's slots] += scale[i * scale_stride] * trilinear weights * dfeat[i * dfeat_stride +
// l * features + f] for every level (scale null: 1), through field::ScatterLevel, the CPU's per-sample
// function; `grads` is the grid's whole gradient array. Threads of a warp whose samples add into the
// same slot one after another (consecutive samples of a ray share their cells at all but the finest
// levels) sum in the warp first, so a run of them costs one atomic add (WarpRunAdd, launch.cuh). When
// dpos_add is not null (table must be given then), also adds dL/dpos (n x 3) to it. Float atomics make
// the sum order (and so the last bits) vary from run to run.
void HashGridBackward(const field::HashGrid<float>& grid, const float* pos, int n, const float* dfeat,
                      int dfeat_stride, const float* scale, int scale_stride, float* grads,
                      const float* table, float* dpos_add);

// --- samplers (one thread per ray) ---

// Draws of ray r come from base::CounterRng<float>(seed, stream_base + stream_step * r), as the
// trainer's (seed = the step's seed, base 1, step 2).
struct RayStreams {
  std::uint64_t seed = 0;
  std::uint64_t stream_base = 0;
  std::uint64_t stream_step = 1;
};

// render::StratifiedSamples over [near, far] for each of n_rays rays: s and delta are n_rays x samples.
void StratifiedSampleRays(float near, float far, int n_rays, int samples, const RayStreams& streams, float* s,
                          float* delta);

// render::DepthGuidedSamples around prior_depth[r] for each ray; samples per ray = the config's
// gaussian_samples + stratified_samples.
void DepthGuidedSampleRays(float near, float far, const float* prior_depth, int n_rays,
                           const render::DepthGuidedConfig<float>& config, const RayStreams& streams,
                           float* s, float* delta);

// --- volume rendering (one thread per ray) ---

// render::CompositeRay for each ray: weights (n_rays x samples) and out[r].
void CompositeRays(const float* sigma, const float* rgb, const float* s, const float* delta, int n_rays,
                   int samples, float min_transmittance, float* weights, render::RayComposite<float>* out);

// render::CompositeRayBackward for each ray, given grad[r] and optionally d_weights (n_rays x samples,
// null for none); ADDS to d_sigma and d_rgb.
void CompositeRaysBackward(const float* sigma, const float* rgb, const float* s, const float* delta,
                           const float* weights, int n_rays, int samples,
                           const render::RayComposite<float>* forward,
                           const render::RayCompositeGrad<float>* grad, const float* d_weights,
                           float* d_sigma, float* d_rgb);

// --- losses (one thread per ray, train/ray_loss.h) ---

// Per ray r: loss[r] = RayLoss of the terms, grad[r] its gradient with respect to the rendered colour
// and depth (overwritten), and ADDED to d_mean_rgb (n_rays x samples x 3) and d_log_var
// (n_rays x samples) the per-sample gradients of the NLL and the regulariser. target_rgb is
// n_rays x 3; prior_depth may be null when depth_scale is 0.
void RayLosses(const render::RayComposite<float>* rays, const float* weights, const float* mean_rgb,
               const float* log_var, const float* target_rgb, const float* prior_depth, int n_rays,
               int samples, const train::RayLossTerms& terms, float* loss,
               render::RayCompositeGrad<float>* grad, float* d_mean_rgb, float* d_log_var);

}  // namespace endorecon::cuda
