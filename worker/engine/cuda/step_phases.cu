#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "worker/engine/cuda/device.h"
#include "worker/engine/cuda/step_phases.h"

namespace endorecon::cuda {

StepPhases::StepPhases() {
  const char* flag = std::getenv("ENDORECON_CUDA_STEP_PHASES");
  on_ = flag != nullptr && std::strcmp(flag, "1") == 0;
}

StepPhases::~StepPhases() {
  if (on_ && steps_ > 0) {
    double total = 0;
    for (const Phase& phase : phases_) total += phase.ms;
    std::fprintf(stderr, "cuda step phases: %d steps, %.3f ms a step:", steps_, total / steps_);
    for (const Phase& phase : phases_) {
      std::fprintf(stderr, " %s %.3f ms (%.0f%%)", phase.name.c_str(), phase.ms / steps_,
                   100 * phase.ms / total);
    }
    std::fprintf(stderr, "\n");
  }
  for (cudaEvent_t event : events_) cudaEventDestroy(event);
}

void StepPhases::Start() {
  if (!on_) return;
  marks_.clear();
  Mark(nullptr);
}

void StepPhases::Mark(const char* phase) {
  if (!on_) return;
  const std::size_t i = marks_.size();
  if (i == events_.size()) {
    events_.emplace_back();
    CheckStatus(cudaEventCreate(&events_.back()), "cudaEventCreate");
  }
  CheckStatus(cudaEventRecord(events_[i]), "cudaEventRecord");
  marks_.push_back(phase);
}

void StepPhases::End() {
  if (!on_ || marks_.size() < 2) return;
  CheckStatus(cudaEventSynchronize(events_[marks_.size() - 1]), "cudaEventSynchronize");
  for (std::size_t i = 1; i < marks_.size(); ++i) {
    float ms = 0;
    CheckStatus(cudaEventElapsedTime(&ms, events_[i - 1], events_[i]), "cudaEventElapsedTime");
    std::size_t p = 0;
    while (p < phases_.size() && phases_[p].name != marks_[i]) ++p;
    if (p == phases_.size()) phases_.push_back({marks_[i], 0});
    phases_[p].ms += ms;
  }
  ++steps_;
}

}  // namespace endorecon::cuda
