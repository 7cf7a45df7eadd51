#include "worker/engine/train/adam.h"

#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <cmath>
#include <istream>
#include <limits>
#include <ostream>

#include "common/error.h"

namespace endorecon::train {

namespace {

// The two passes over every parameter of a step, written so the compiler vectorises them: they were
// a tenth of a CPU step as scalar loops (docs/benchmarks.md, "The optimiser's passes, vectorised").

// Sum of squares (in double) and largest magnitude of n gradients, in kLanes independent partial
// results: a single running sum is a chain the compiler may not reorder, lanes are not.
GradientNorms RangeNorms(const float* grad, std::size_t n) {
  constexpr std::size_t kLanes = 16;
  double sq[kLanes] = {};
  float max[kLanes] = {};
  std::size_t i = 0;
  for (; i + kLanes <= n; i += kLanes) {
    for (std::size_t l = 0; l < kLanes; ++l) {
      const float x = grad[i + l];
      sq[l] += double(x) * x;
      max[l] = std::max(max[l], std::fabs(x));
    }
  }
  for (; i < n; ++i) {
    sq[0] += double(grad[i]) * grad[i];
    max[0] = std::max(max[0], std::fabs(grad[i]));
  }
  GradientNorms norms;
  for (std::size_t l = 0; l < kLanes; ++l) {
    norms.sq += sq[l];
    norms.max = std::max(norms.max, double(max[l]));
  }
  return norms;
}

// AdamUpdate over n parameters. The arrays never overlap, and the coefficients are a copy, so no
// store can change them: what lets the loop run in vector registers.
void UpdateRange(float* __restrict value, const float* __restrict grad, float* __restrict m,
                 float* __restrict v, std::size_t n, const AdamCoefficients coefficients) {
  for (std::size_t i = 0; i < n; ++i) AdamUpdate(value[i], grad[i], m[i], v[i], coefficients);
}

}  // namespace

Adam::Adam(std::vector<field::ParamBlock<float>> groups, AdamConfig config)
    : groups_(std::move(groups)), config_(std::move(config)) {
  for (const auto& g : groups_) {
    m_.emplace_back(g.size, 0.0f);
    v_.emplace_back(g.size, 0.0f);
  }
}

StepPlan PlanStep(const std::vector<GradientNorms>& norms,
                  const std::vector<field::ParamBlock<float>>& blocks, const AdamConfig& config) {
  StepPlan plan;
  double sum_sq = 0;
  for (std::size_t k = 0; k < norms.size(); ++k) {
    if ((!std::isfinite(norms[k].sq) || !std::isfinite(norms[k].max)) && plan.report.finite) {
      plan.report.finite = false;
      plan.report.bad_group = blocks[k].name;
    }
    sum_sq += norms[k].sq;
  }
  plan.report.grad_norm = std::sqrt(sum_sq);
  if (!plan.report.finite) return plan;
  if (config.clip_norm > 0 && plan.report.grad_norm > config.clip_norm) {
    plan.scale = static_cast<float>(config.clip_norm / plan.report.grad_norm);
  }
  const double largest = std::sqrt(double(std::numeric_limits<float>::max()));
  for (std::size_t k = 0; k < norms.size(); ++k) {
    if (norms[k].max * plan.scale > largest) {
      plan.report.finite = false;
      plan.report.bad_group = blocks[k].name;
      return plan;
    }
  }
  return plan;
}

AdamCoefficients CoefficientsFor(const AdamConfig& config, const std::string& name, long long steps,
                                 double progress, float scale) {
  const float decay =
      static_cast<float>(std::pow(double(config.final_lr_factor), std::clamp(progress, 0.0, 1.0)));
  const float c1 = 1.0f - static_cast<float>(std::pow(double(config.beta1), double(steps)));
  const float c2 = 1.0f - static_cast<float>(std::pow(double(config.beta2), double(steps)));
  const auto it = config.lr.find(name);
  const float lr = (it == config.lr.end() ? config.default_lr : it->second) * decay;
  return {config.beta1, config.beta2, lr * std::sqrt(c2) / c1, config.eps * std::sqrt(c2), scale};
}

void WriteAdamHeader(std::ostream& out, long long steps, std::size_t blocks) {
  const std::uint64_t count = blocks;
  out.write(reinterpret_cast<const char*>(&steps), sizeof(steps));
  out.write(reinterpret_cast<const char*>(&count), sizeof(count));
}

void WriteAdamBlock(std::ostream& out, std::uint64_t size, const float* m, const float* v) {
  out.write(reinterpret_cast<const char*>(&size), sizeof(size));
  out.write(reinterpret_cast<const char*>(m), std::streamsize(size * sizeof(float)));
  out.write(reinterpret_cast<const char*>(v), std::streamsize(size * sizeof(float)));
}

long long ReadAdamHeader(std::istream& in, std::size_t blocks) {
  long long steps = 0;
  std::uint64_t count = 0;
  in.read(reinterpret_cast<char*>(&steps), sizeof(steps));
  in.read(reinterpret_cast<char*>(&count), sizeof(count));
  if (!in || count != blocks) Fail(ErrorCode::kDataLoss, "optimiser state: group count mismatch");
  return steps;
}

void ReadAdamBlock(std::istream& in, const field::ParamBlock<float>& block, float* m, float* v) {
  std::uint64_t size = 0;
  in.read(reinterpret_cast<char*>(&size), sizeof(size));
  if (!in || size != block.size)
    Fail(ErrorCode::kDataLoss, "optimiser state: size mismatch in group " + block.name);
  in.read(reinterpret_cast<char*>(m), std::streamsize(size * sizeof(float)));
  in.read(reinterpret_cast<char*>(v), std::streamsize(size * sizeof(float)));
  if (!in) Fail(ErrorCode::kDataLoss, "optimiser state: truncated in group " + block.name);
}

AdamStepReport Adam::Step(double progress) {
  std::vector<GradientNorms> norms(groups_.size());
  const auto join = [](const GradientNorms& a, const GradientNorms& b) {
    return GradientNorms{a.sq + b.sq, std::max(a.max, b.max)};
  };
  for (std::size_t k = 0; k < groups_.size(); ++k) {
    const auto& g = groups_[k];
    // Over blocks in parallel (a serial pass over the ~10^6 grid gradients left the second core idle
    // for a few per cent of every step).
    norms[k] = tbb::parallel_reduce(
        tbb::blocked_range<std::size_t>(0, g.size, 1 << 14), GradientNorms{},
        [&](const tbb::blocked_range<std::size_t>& r, const GradientNorms& acc) {
          return join(acc, RangeNorms(g.grad + r.begin(), r.size()));
        },
        join);
  }
  const StepPlan plan = PlanStep(norms, groups_, config_);
  if (!plan.report.finite) return plan.report;
  ++steps_;
  for (std::size_t k = 0; k < groups_.size(); ++k) {
    const auto& g = groups_[k];
    const AdamCoefficients coefficients = CoefficientsFor(config_, g.name, steps_, progress, plan.scale);
    float* m = m_[k].data();
    float* v = v_[k].data();
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, g.size, 1 << 14), [&](const auto& r) {
      const std::size_t i = r.begin();
      UpdateRange(g.value + i, g.grad + i, m + i, v + i, r.size(), coefficients);
    });
  }
  return plan.report;
}

void Adam::Save(std::ostream& out) const {
  WriteAdamHeader(out, steps_, groups_.size());
  for (std::size_t k = 0; k < groups_.size(); ++k)
    WriteAdamBlock(out, groups_[k].size, m_[k].data(), v_[k].data());
}

void Adam::Load(std::istream& in) {
  steps_ = ReadAdamHeader(in, groups_.size());
  for (std::size_t k = 0; k < groups_.size(); ++k) ReadAdamBlock(in, groups_[k], m_[k].data(), v_[k].data());
}

}  // namespace endorecon::train
