#include <algorithm>
#include <cstring>
#include <istream>
#include <ostream>
#include <string>
#include <vector>

#include "common/error.h"
#include "worker/engine/cuda/device.h"
#include "worker/engine/cuda/device_adam.h"
#include "worker/engine/cuda/launch.cuh"

namespace endorecon::cuda {
namespace {

// *sum_sq += the sum of squares of grad[0..n) (double), *max_bits = max(*max_bits, max |g|) (as the
// float's bits: non-negative floats order as their bit patterns, so an integer atomicMax finds the
// largest; NaN counts as Inf). Each thread block reduces its grid-stride share in shared memory and
// adds it with one atomic, so a block of parameters costs a few hundred atomics, not one per value.
__global__ void NormKernel(const float* grad, std::size_t n, double* sum_sq, unsigned* max_bits) {
  __shared__ double sums[kThreads];
  __shared__ unsigned maxes[kThreads];
  double sum = 0;
  unsigned largest = 0;
  for (std::size_t i = ThreadIndex(); i < n; i += std::size_t(gridDim.x) * blockDim.x) {
    const float g = grad[i];
    sum += double(g) * double(g);
    const float a = fabsf(g);
    largest = max(largest, a == a ? __float_as_uint(a) : 0x7f800000u);
  }
  sums[threadIdx.x] = sum;
  maxes[threadIdx.x] = largest;
  __syncthreads();
  for (unsigned stride = blockDim.x / 2; stride > 0; stride /= 2) {
    if (threadIdx.x < stride) {
      sums[threadIdx.x] += sums[threadIdx.x + stride];
      maxes[threadIdx.x] = max(maxes[threadIdx.x], maxes[threadIdx.x + stride]);
    }
    __syncthreads();
  }
  if (threadIdx.x == 0) {
    atomicAdd(sum_sq, sums[0]);
    atomicMax(max_bits, maxes[0]);
  }
}

// Every group's update in one launch: the groups' arrays and coefficients travel as the kernel's
// parameters (a few hundred bytes), element i of the concatenation belongs to the group whose range
// holds it.
inline constexpr int kMaxGroups = 16;
struct GroupTable {
  std::size_t end[kMaxGroups] = {};  // cumulative sizes
  float* value[kMaxGroups] = {};
  const float* grad[kMaxGroups] = {};
  float* m[kMaxGroups] = {};
  float* v[kMaxGroups] = {};
  train::AdamCoefficients c[kMaxGroups] = {};
};

__global__ void UpdateKernel(GroupTable t, std::size_t total) {
  const std::size_t i = ThreadIndex();
  if (i >= total) return;
  int k = 0;
  while (i >= t.end[k]) ++k;
  const std::size_t j = i - (k == 0 ? 0 : t.end[k - 1]);
  train::AdamUpdate(t.value[k][j], t.grad[k][j], t.m[k][j], t.v[k][j], t.c[k]);
}

// Thread blocks for a norm over n values: enough to fill a large GPU, each taking a grid-stride share.
unsigned NormBlocks(std::size_t n) { return std::min(Blocks(n), 1024u); }

}  // namespace

struct DeviceAdam::Impl {
  std::vector<field::ParamBlock<float>> blocks;
  train::AdamConfig config;
  std::vector<DeviceArray<float>> m, v;
  DeviceArray<double> sum_sq;      // per group
  DeviceArray<unsigned> max_bits;  // per group
  long long steps = 0;
};

DeviceAdam::DeviceAdam(std::vector<field::ParamBlock<float>> blocks, train::AdamConfig config)
    : impl_(std::make_unique<Impl>()) {
  impl_->blocks = std::move(blocks);
  impl_->config = std::move(config);
  if (impl_->blocks.size() > std::size_t(kMaxGroups)) {
    FailInvalid("DeviceAdam: " + std::to_string(impl_->blocks.size()) + " parameter groups, at most " +
                std::to_string(kMaxGroups));
  }
  impl_->sum_sq = DeviceArray<double>(impl_->blocks.size());
  impl_->max_bits = DeviceArray<unsigned>(impl_->blocks.size());
  for (const auto& b : impl_->blocks) {
    impl_->m.emplace_back(b.size);
    impl_->v.emplace_back(b.size);
    impl_->m.back().Zero();
    impl_->v.back().Zero();
  }
}

DeviceAdam::~DeviceAdam() = default;

train::AdamStepReport DeviceAdam::Step(double progress) {
  Impl& a = *impl_;
  // Every group's norms, then one copy of each group's two scalars back.
  a.sum_sq.Zero();
  a.max_bits.Zero();
  for (std::size_t k = 0; k < a.blocks.size(); ++k) {
    const auto& b = a.blocks[k];
    if (b.size == 0) continue;
    NormKernel<<<NormBlocks(b.size), kThreads>>>(b.grad, b.size, a.sum_sq.data() + k, a.max_bits.data() + k);
    CheckLaunch("gradient norm kernel");
  }
  const std::vector<double> sums = a.sum_sq.Download();
  const std::vector<unsigned> bits = a.max_bits.Download();
  std::vector<train::GradientNorms> norms(a.blocks.size());
  for (std::size_t k = 0; k < a.blocks.size(); ++k) {
    float largest = 0;
    std::memcpy(&largest, &bits[k], sizeof(largest));
    norms[k] = {sums[k], largest};
  }
  const train::StepPlan plan = train::PlanStep(norms, a.blocks, a.config);
  if (!plan.report.finite) return plan.report;
  ++a.steps;
  GroupTable table;
  std::size_t total = 0;
  for (std::size_t k = 0; k < a.blocks.size(); ++k) {
    const auto& b = a.blocks[k];
    total += b.size;
    table.end[k] = total;
    table.value[k] = b.value;
    table.grad[k] = b.grad;
    table.m[k] = a.m[k].data();
    table.v[k] = a.v[k].data();
    table.c[k] = train::CoefficientsFor(a.config, b.name, a.steps, progress, plan.scale);
  }
  if (total > 0) {
    UpdateKernel<<<Blocks(total), kThreads>>>(table, total);
    CheckLaunch("Adam update kernel");
  }
  return plan.report;
}

void DeviceAdam::Save(std::ostream& out) const {
  const Impl& a = *impl_;
  train::WriteAdamHeader(out, a.steps, a.blocks.size());
  for (std::size_t k = 0; k < a.blocks.size(); ++k) {
    train::WriteAdamBlock(out, a.blocks[k].size, a.m[k].Download().data(), a.v[k].Download().data());
  }
}

void DeviceAdam::Load(std::istream& in) {
  Impl& a = *impl_;
  a.steps = train::ReadAdamHeader(in, a.blocks.size());
  for (std::size_t k = 0; k < a.blocks.size(); ++k) {
    std::vector<float> m(a.blocks[k].size), v(a.blocks[k].size);
    train::ReadAdamBlock(in, a.blocks[k], m.data(), v.data());
    a.m[k].Upload(m);
    a.v[k].Upload(v);
  }
}

}  // namespace endorecon::cuda
