// Adam with per-group learning rates, exponential decay and optional global-norm gradient clipping.
#pragma once

#include <iosfwd>
#include <map>
#include <string>
#include <vector>

#include "worker/engine/field/param_block.h"

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
