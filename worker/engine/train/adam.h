// Adam with per-group learning rates, exponential decay and optional global-norm gradient clipping.
#pragma once

#include <cstdint>
#include <iosfwd>
#include <map>
#include <string>
#include <vector>

#include "worker/engine/field/param_block.h"
#include "worker/engine/train/adam_math.h"

namespace endorecon::train {

struct AdamConfig {
  std::map<std::string, float> lr;  // per group name; a group missing here uses default_lr
  float default_lr = 1e-3f;
  float beta1 = 0.9f, beta2 = 0.99f, eps = 1e-10f;
  float final_lr_factor = 0.1f;  // lr decays exponentially to lr * factor at the last iteration
  float clip_norm = 0.0f;        // global gradient-norm clip; 0 = off
};

struct AdamStepReport {
  double grad_norm = 0;  // before clipping
  // false: some gradient was NaN/Inf, or (after clipping) so large that its square overflows float;
  // nothing was updated
  bool finite = true;
  std::string bad_group;  // the first group holding such a gradient
};

// What train::Adam and cuda::DeviceAdam share on the host, so the two differ only in where the
// loops run.
// One block's gradient over a step: the sum of squares (in double: a gradient the clipping can
// still rescue, above sqrt(FLT_MAX), must not read as Inf) and the largest magnitude.
struct GradientNorms {
  double sq = 0, max = 0;
};
struct StepPlan {
  AdamStepReport report;
  float scale = 1;  // gradient clipping's factor
};
// The report and the clip scale of a step from each block's norms: not finite when a block's
// gradient is NaN/Inf, or when after clipping its largest value's square would overflow the float
// second moment (which would freeze that parameter for good, m / sqrt(Inf) = 0, without any NaN).
StepPlan PlanStep(const std::vector<GradientNorms>& norms,
                  const std::vector<field::ParamBlock<float>>& blocks, const AdamConfig& config);
// The update coefficients of block `name` at step `steps` (counted from 1) and run `progress`.
AdamCoefficients CoefficientsFor(const AdamConfig& config, const std::string& name, long long steps,
                                 double progress, float scale);
// The optimiser state's stream format: steps and block count, then per block its size, m and v.
void WriteAdamHeader(std::ostream& out, long long steps, std::size_t blocks);
void WriteAdamBlock(std::ostream& out, std::uint64_t size, const float* m, const float* v);
// Throw Error(kDataLoss) on another block count, another size or a truncated stream.
long long ReadAdamHeader(std::istream& in, std::size_t blocks);
void ReadAdamBlock(std::istream& in, const field::ParamBlock<float>& block, float* m, float* v);

class Adam {
 public:
  Adam(std::vector<field::ParamBlock<float>> groups, AdamConfig config);

  // One update from the gradients currently in the groups, at `progress` in [0, 1] of the run (the
  // learning rate decays with it). Does nothing (and says so) when a gradient is not finite, so a bad
  // step never reaches the parameters.
  AdamStepReport Step(double progress);

  void Save(std::ostream& out) const;
  void Load(std::istream& in);  // throws Error(kDataLoss) on a mismatched or truncated state

 private:
  std::vector<field::ParamBlock<float>> groups_;
  AdamConfig config_;
  std::vector<std::vector<float>> m_, v_;
  long long steps_ = 0;
};

}  // namespace endorecon::train
