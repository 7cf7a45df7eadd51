#include <cstring>
#include <istream>
#include <ostream>

#include "worker/engine/cuda/device.h"
#include "worker/engine/cuda/device_adam.h"
#include "worker/engine/cuda/launch.cuh"

namespace endorecon::cuda {
namespace {

// norms[0] += sum of squares (double), norms[1] = max |g| (as the float's bits: non-negative floats
// order as their bit patterns, so an integer atomicMax finds the largest).
__global__ void NormKernel(const float* grad, std::size_t n, double* sum_sq, unsigned* max_bits) {
  const std::size_t i = ThreadIndex();
  if (i >= n) return;
  const float g = grad[i];
  atomicAdd(sum_sq, double(g) * double(g));
  const float a = fabsf(g);
  atomicMax(max_bits, a == a ? __float_as_uint(a) : 0x7f800000u);  // NaN counts as Inf
}

__global__ void UpdateKernel(float* value, const float* grad, float* m, float* v, std::size_t n,
                             train::AdamCoefficients c) {
  const std::size_t i = ThreadIndex();
  if (i < n) train::AdamUpdate(value[i], grad[i], m[i], v[i], c);
}

}  // namespace

struct DeviceAdam::Impl {
  std::vector<field::ParamBlock<float>> blocks;
  train::AdamConfig config;
  std::vector<DeviceArray<float>> m, v;
  DeviceArray<double> sum_sq{1};
  DeviceArray<unsigned> max_bits{1};
  long long steps = 0;
};

DeviceAdam::DeviceAdam(std::vector<field::ParamBlock<float>> blocks, train::AdamConfig config)
    : impl_(std::make_unique<Impl>()) {
  impl_->blocks = std::move(blocks);
  impl_->config = std::move(config);
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
  std::vector<train::GradientNorms> norms(a.blocks.size());
  for (std::size_t k = 0; k < a.blocks.size(); ++k) {
    const auto& b = a.blocks[k];
    a.sum_sq.Zero();
    a.max_bits.Zero();
    NormKernel<<<Blocks(b.size), kThreads>>>(b.grad, b.size, a.sum_sq.data(), a.max_bits.data());
    CheckLaunch("gradient norm kernel");
    const unsigned bits = a.max_bits.Download()[0];
    float max = 0;
    std::memcpy(&max, &bits, sizeof(max));
    norms[k] = {a.sum_sq.Download()[0], max};
  }
  const train::StepPlan plan = train::PlanStep(norms, a.blocks, a.config);
  if (!plan.report.finite) return plan.report;
  ++a.steps;
  for (std::size_t k = 0; k < a.blocks.size(); ++k) {
    const auto& b = a.blocks[k];
    UpdateKernel<<<Blocks(b.size), kThreads>>>(
        b.value, b.grad, a.m[k].data(), a.v[k].data(), b.size,
        train::CoefficientsFor(a.config, b.name, a.steps, progress, plan.scale));
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
