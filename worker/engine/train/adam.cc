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

Adam::Adam(std::vector<field::ParamBlock<float>> groups, AdamConfig config)
    : groups_(std::move(groups)), config_(std::move(config)) {
  for (const auto& g : groups_) {
    m_.emplace_back(g.size, 0.0f);
    v_.emplace_back(g.size, 0.0f);
  }
}

AdamStepReport Adam::Step(double progress) {
  AdamStepReport report;
  double sum_sq = 0;
  std::vector<double> group_max(groups_.size(), 0.0);
  for (std::size_t k = 0; k < groups_.size(); ++k) {
    const auto& g = groups_[k];
    // Sum of squares and largest magnitude, over blocks in parallel (a serial pass over the ~10^6
    // grid gradients left the second core idle for a few per cent of every step).
    struct Norms {
      double sq = 0, max = 0;
    };
    const Norms norms = tbb::parallel_reduce(
        tbb::blocked_range<std::size_t>(0, g.size, 1 << 14), Norms{},
        [&](const tbb::blocked_range<std::size_t>& r, Norms acc) {
          // Squares in double: a gradient the clipping can still rescue (above sqrt(FLT_MAX)) must not
          // read as Inf here.
          double sq = 0;
          float max = 0;
          for (std::size_t i = r.begin(); i != r.end(); ++i) {
            sq += double(g.grad[i]) * g.grad[i];
            max = std::max(max, std::fabs(g.grad[i]));
          }
          acc.sq += sq;
          acc.max = std::max(acc.max, double(max));
          return acc;
        },
        [](Norms a, const Norms& b) {
          return Norms{a.sq + b.sq, std::max(a.max, b.max)};
        });
    const double group_sq = norms.sq;
    group_max[k] = norms.max;
    if (!std::isfinite(group_sq) && report.finite) {
      report.finite = false;
      report.bad_group = g.name;
    }
    sum_sq += group_sq;
  }
  report.grad_norm = std::sqrt(sum_sq);
  if (!report.finite) return report;

  float scale = 1.0f;
  if (config_.clip_norm > 0 && report.grad_norm > config_.clip_norm) {
    scale = static_cast<float>(config_.clip_norm / report.grad_norm);
  }
  // The second moment is kept in float: a (scaled) gradient above sqrt(FLT_MAX) would make it Inf and
  // freeze that parameter for good (m / sqrt(Inf) = 0) without any NaN. Refuse the step instead.
  const double largest = std::sqrt(double(std::numeric_limits<float>::max()));
  for (std::size_t k = 0; k < groups_.size(); ++k) {
    if (group_max[k] * scale > largest) {
      report.finite = false;
      report.bad_group = groups_[k].name;
      return report;
    }
  }
  ++steps_;
  const float decay =
      static_cast<float>(std::pow(double(config_.final_lr_factor), std::clamp(progress, 0.0, 1.0)));
  const float b1 = config_.beta1, b2 = config_.beta2;
  const float c1 = 1.0f - static_cast<float>(std::pow(double(b1), double(steps_)));
  const float c2 = 1.0f - static_cast<float>(std::pow(double(b2), double(steps_)));
  for (std::size_t k = 0; k < groups_.size(); ++k) {
    const auto& g = groups_[k];
    auto it = config_.lr.find(g.name);
    const float lr = (it == config_.lr.end() ? config_.default_lr : it->second) * decay;
    const float step = lr * std::sqrt(c2) / c1;
    float* m = m_[k].data();
    float* v = v_[k].data();
    const float eps = config_.eps * std::sqrt(c2);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, g.size, 1 << 14), [&](const auto& r) {
      for (std::size_t i = r.begin(); i != r.end(); ++i) {
        const float grad = g.grad[i] * scale;
        m[i] = b1 * m[i] + (1 - b1) * grad;
        v[i] = b2 * v[i] + (1 - b2) * grad * grad;
        g.value[i] -= step * m[i] / (std::sqrt(v[i]) + eps);
      }
    });
  }
  return report;
}

void Adam::Save(std::ostream& out) const {
  const std::uint64_t count = groups_.size();
  out.write(reinterpret_cast<const char*>(&steps_), sizeof(steps_));
  out.write(reinterpret_cast<const char*>(&count), sizeof(count));
  for (std::size_t k = 0; k < groups_.size(); ++k) {
    const std::uint64_t size = groups_[k].size;
    out.write(reinterpret_cast<const char*>(&size), sizeof(size));
    out.write(reinterpret_cast<const char*>(m_[k].data()), std::streamsize(size * sizeof(float)));
    out.write(reinterpret_cast<const char*>(v_[k].data()), std::streamsize(size * sizeof(float)));
  }
}

void Adam::Load(std::istream& in) {
  std::uint64_t count = 0;
  in.read(reinterpret_cast<char*>(&steps_), sizeof(steps_));
  in.read(reinterpret_cast<char*>(&count), sizeof(count));
  if (!in || count != groups_.size()) Fail(ErrorCode::kDataLoss, "optimiser state: group count mismatch");
  for (std::size_t k = 0; k < groups_.size(); ++k) {
    std::uint64_t size = 0;
    in.read(reinterpret_cast<char*>(&size), sizeof(size));
    if (!in || size != groups_[k].size) {
      Fail(ErrorCode::kDataLoss, "optimiser state: size mismatch in group " + groups_[k].name);
    }
    in.read(reinterpret_cast<char*>(m_[k].data()), std::streamsize(size * sizeof(float)));
    in.read(reinterpret_cast<char*>(v_[k].data()), std::streamsize(size * sizeof(float)));
    if (!in) Fail(ErrorCode::kDataLoss, "optimiser state: truncated in group " + groups_[k].name);
  }
}

}  // namespace endorecon::train
