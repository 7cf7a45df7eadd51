#include "worker/engine/run_config.h"

#include "common/error.h"
#include "worker/engine/device_description.h"
#ifdef ENDORECON_WITH_CUDA
#include "worker/engine/cuda/device_render.h"
#include "worker/engine/cuda/device_step.h"
#include "worker/engine/cuda/shared_fields.h"
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
  // With a budget the schedule runs on time and the iteration count is a cap only when given.
  if (options.iterations > 0) {
    config.iterations = options.iterations;
  } else if (options.time_budget_s > 0) {
    config.iterations = 0;
  } else if (config.iterations == 0) {  // a checkpoint of a budgeted run, resumed without one
    config.iterations = train::TrainConfig::Preset(options.preset).iterations;
  }
  if (options.holdout >= 0) config.holdout = options.holdout;
  if (config.holdout == 1) {
    FailInvalid(
        "holdout 1 would hold every frame out of training: 0 holds none out, K >= 2 every K-th frame");
  }
  return config;
}

FrameSplit SplitFrames(int frames, int holdout) {
  FrameSplit split;
  for (int f = 0; f < frames; ++f) {
    (holdout > 1 && (f + 1) % holdout == 0 ? split.heldout : split.train).push_back(f);
  }
  return split;
}

DeviceBackends BackendsFor(const std::string& device) {
  if (device == "cpu") return {train::MakeCpuStep, render::MakeCpuRender};
    // DescribeDevice refuses, naming the reason, a device this build or machine cannot run.
#ifdef ENDORECON_WITH_CUDA
  const int index = DescribeDevice(device).cuda_index;
  // The steps and the renders of a run share the device copy of its field (no copies between them).
  const auto shared = std::make_shared<cuda::SharedFields>();
  return {cuda::DeviceStepFactory(index, shared), cuda::DeviceRenderFactory(index, shared)};
#else
  DescribeDevice(device);
  Fail(ErrorCode::kInternal, "DescribeDevice accepted " + device + " in a build without CUDA");
#endif
}

nlohmann::json RunConfigJson(const train::TrainConfig& config, const ReconstructOptions& options,
                             int threads) {
  nlohmann::json json{
      {"train", train::ToJson(config)},         {"clip", options.clip_dir}, {"seed", options.seed},
      {"time_budget_s", options.time_budget_s}, {"threads", threads},       {"device", options.device}};
  if (!options.title.empty()) json["title"] = options.title;
  if (!options.frames.SelectsAll()) json["frames"] = options.frames.ToString();
  return json;
}

}  // namespace endorecon
