#include "worker/engine/run_config.h"

#include "common/error.h"
#ifdef ENDORECON_WITH_CUDA
#include "worker/engine/cuda/device.h"
#include "worker/engine/cuda/device_step.h"
#endif
#include "worker/engine/train/checkpoint.h"

namespace endorecon {

train::TrainConfig ResolveConfig(const ReconstructOptions& options) {
  train::TrainConfig config = options.resume_from.empty() ? train::TrainConfig::Preset(options.preset)
                                                          : train::ReadCheckpointConfig(options.resume_from);
  if (!options.config.is_object()) {
    FailInvalid("the run's configuration must be a JSON object of training keys, got " +
                options.config.dump());
  }
  train::ApplyJson(options.config, config);
  if (options.iterations > 0) config.iterations = options.iterations;
  if (options.holdout >= 0) config.holdout = options.holdout;
  return config;
}

FrameSplit SplitFrames(int frames, int holdout) {
  FrameSplit split;
  for (int f = 0; f < frames; ++f) {
    (holdout > 1 && (f + 1) % holdout == 0 ? split.heldout : split.train).push_back(f);
  }
  return split;
}

train::StepBackendFactory BackendFor(const std::string& device) {
  if (device == "cpu") return train::MakeCpuStep;
  const std::string prefix = "cuda:";
  const std::string number = device.rfind(prefix, 0) == 0 ? device.substr(prefix.size()) : "";
  if (number.empty() || number.size() > 3 || number.find_first_not_of("0123456789") != std::string::npos) {
    FailInvalid("device '" + device + "': expected cpu or cuda:N (N a CUDA device index)");
  }
#ifdef ENDORECON_WITH_CUDA
  const int index = std::stoi(number);
  const cuda::DeviceList list = cuda::ListDevices();
  if (index >= static_cast<int>(list.devices.size())) {
    FailInvalid("device " + device + ": no such CUDA device (" +
                (list.problem.empty() ? std::to_string(list.devices.size()) + " found" : list.problem) + ")");
  }
  return cuda::DeviceStepFactory(index);
#else
  FailInvalid("device " + device + ": this build has no CUDA engine (it was built without a CUDA toolkit)");
#endif
}

nlohmann::json RunConfigJson(const train::TrainConfig& config, const ReconstructOptions& options,
                             int threads) {
  return {{"train", train::ToJson(config)},         {"clip", options.clip_dir}, {"seed", options.seed},
          {"time_budget_s", options.time_budget_s}, {"threads", threads},       {"device", options.device}};
}

}  // namespace endorecon
