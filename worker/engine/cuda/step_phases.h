// Where a GPU training step's time goes, phase by phase, without a profiler (kernel by kernel, where
// Nsight Compute is installed: `gpu-bundle/run kernels`): with ENDORECON_CUDA_STEP_PHASES=1, CUDA events
// are recorded between a step's phases and read back at its end (one extra synchronisation a step),
// and the mean milliseconds per step of each phase go to stderr when the step backend closes.
// Without it, every call returns at once. Included by .cu files only.
#pragma once

#include <cuda_runtime.h>

#include <string>
#include <vector>

namespace endorecon::cuda {

class StepPhases {
 public:
  StepPhases();  // reads ENDORECON_CUDA_STEP_PHASES
  ~StepPhases();
  StepPhases(const StepPhases&) = delete;
  StepPhases& operator=(const StepPhases&) = delete;

  void Start();                  // a step begins
  void Mark(const char* phase);  // `phase` ends here
  void End();                    // the step ends: waits for its work and adds up its phases

 private:
  struct Phase {
    std::string name;
    double ms = 0;
  };
  bool on_ = false;
  int steps_ = 0;
  std::vector<cudaEvent_t> events_;  // one per mark of the current step, the start first
  std::vector<const char*> marks_;   // the current step's phases, in order
  std::vector<Phase> phases_;        // totals, in the order first seen
};

}  // namespace endorecon::cuda
