#include "worker/runtime/job_options.h"

#include "common/error.h"
#include "common/json_file.h"

namespace endorecon::worker {

ReconstructOptions OptionsFor(const v1::Job& job, const std::filesystem::path& job_dir,
                              const Device& device) {
  const auto& o = job.options();
  ReconstructOptions options;
  options.clip_dir = (job_dir / "clip").string();
  options.out_dir = (job_dir / "out").string();
  if (!o.config_json().empty()) {
    options.config = ParseJson(o.config_json(), "job " + job.id() + ": its config");
    if (!options.config.is_object()) FailInvalid("job " + job.id() + ": its config must be a JSON object");
  }
  if (!o.preset().empty()) options.preset = o.preset();
  if (o.has_iterations()) options.iterations = o.iterations();
  options.time_budget_s = o.time_budget_s();
  if (o.has_holdout()) options.holdout = o.holdout();
  options.seed = o.seed();
  options.force_static = o.force_static();
  options.title = job.name().empty() ? "job " + job.id() : job.name();
  options.threads = device.threads;
  options.device = device.EngineDevice();
  if (job.has_checkpoint() && !job.checkpoint().sha256().empty()) {
    options.resume_from = (job_dir / "checkpoint" / job.checkpoint().path()).string();
  }
  return options;
}

}  // namespace endorecon::worker
