#include <algorithm>
#include <cmath>
#include <cstring>
#include <istream>
#include <limits>
#include <ostream>

#include "common/error.h"
#include "worker/engine/cuda/device.h"
#include "worker/engine/cuda/device_adam.h"
#include "worker/engine/cuda/launch.cuh"
#include "worker/engine/train/adam_math.h"

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
  train::AdamStepReport report;
  double total_sq = 0;
  std::vector<double> group_max(a.blocks.size(), 0.0);
  for (std::size_t k = 0; k < a.blocks.size(); ++k) {
    const auto& b = a.blocks[k];
    a.sum_sq.Zero();
    a.max_bits.Zero();
    NormKernel<<<Blocks(b.size), kThreads>>>(b.grad, b.size, a.sum_sq.data(), a.max_bits.data());
    CheckLaunch("gradient norm kernel");
    const double sq = a.sum_sq.Download()[0];
    const unsigned bits = a.max_bits.Download()[0];
    float max = 0;
    std::memcpy(&max, &bits, sizeof(max));
    group_max[k] = max;
    if ((!std::isfinite(sq) || !std::isfinite(max)) && report.finite) {
      report.finite = false;
      report.bad_group = b.name;
    }
    total_sq += sq;
  }
  report.grad_norm = std::sqrt(total_sq);
  if (!report.finite) return report;
  float scale = 1.0f;
  if (a.config.clip_norm > 0 && report.grad_norm > a.config.clip_norm) {
    scale = static_cast<float>(a.config.clip_norm / report.grad_norm);
  }
  const double largest = std::sqrt(double(std::numeric_limits<float>::max()));
  for (std::size_t k = 0; k < a.blocks.size(); ++k) {
    if (group_max[k] * scale > largest) {
      report.finite = false;
      report.bad_group = a.blocks[k].name;
      return report;
    }
  }
  ++a.steps;
  const float decay =
      static_cast<float>(std::pow(double(a.config.final_lr_factor), std::clamp(progress, 0.0, 1.0)));
  const float c1 = 1.0f - static_cast<float>(std::pow(double(a.config.beta1), double(a.steps)));
  const float c2 = 1.0f - static_cast<float>(std::pow(double(a.config.beta2), double(a.steps)));
  for (std::size_t k = 0; k < a.blocks.size(); ++k) {
    const auto& b = a.blocks[k];
    const auto it = a.config.lr.find(b.name);
    const float lr = (it == a.config.lr.end() ? a.config.default_lr : it->second) * decay;
    const train::AdamCoefficients coefficients{a.config.beta1, a.config.beta2, lr * std::sqrt(c2) / c1,
                                               a.config.eps * std::sqrt(c2), scale};
    UpdateKernel<<<Blocks(b.size), kThreads>>>(b.value, b.grad, a.m[k].data(), a.v[k].data(), b.size,
                                               coefficients);
    CheckLaunch("Adam update kernel");
  }
  return report;
}

void DeviceAdam::Save(std::ostream& out) const {
  const Impl& a = *impl_;
  const std::uint64_t count = a.blocks.size();
  out.write(reinterpret_cast<const char*>(&a.steps), sizeof(a.steps));
  out.write(reinterpret_cast<const char*>(&count), sizeof(count));
  for (std::size_t k = 0; k < a.blocks.size(); ++k) {
    const std::uint64_t size = a.blocks[k].size;
    out.write(reinterpret_cast<const char*>(&size), sizeof(size));
    for (const auto* moment : {&a.m[k], &a.v[k]}) {
      const std::vector<float> host = moment->Download();
      out.write(reinterpret_cast<const char*>(host.data()), std::streamsize(size * sizeof(float)));
    }
  }
}

void DeviceAdam::Load(std::istream& in) {
  Impl& a = *impl_;
  std::uint64_t count = 0;
  in.read(reinterpret_cast<char*>(&a.steps), sizeof(a.steps));
  in.read(reinterpret_cast<char*>(&count), sizeof(count));
  if (!in || count != a.blocks.size()) Fail(ErrorCode::kDataLoss, "optimiser state: group count mismatch");
  for (std::size_t k = 0; k < a.blocks.size(); ++k) {
    std::uint64_t size = 0;
    in.read(reinterpret_cast<char*>(&size), sizeof(size));
    if (!in || size != a.blocks[k].size) {
      Fail(ErrorCode::kDataLoss, "optimiser state: size mismatch in group " + a.blocks[k].name);
    }
    for (auto* moment : {&a.m[k], &a.v[k]}) {
      std::vector<float> host(size);
      in.read(reinterpret_cast<char*>(host.data()), std::streamsize(size * sizeof(float)));
      if (!in) Fail(ErrorCode::kDataLoss, "optimiser state: truncated in group " + a.blocks[k].name);
      moment->Upload(host);
    }
  }
}

}  // namespace endorecon::cuda
