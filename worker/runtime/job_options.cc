#include "worker/runtime/job_options.h"

#include "common/error.h"

namespace endorecon::worker {

ReconstructOptions OptionsFor(const v1::Job& job, const std::filesystem::path& job_dir,
                              const Device& device) {
  const auto& o = job.options();
  ReconstructOptions options;
  options.clip_dir = (job_dir / "clip").string();
  options.out_dir = (job_dir / "out").string();
  if (!o.config_json().empty()) {
    try {
      options.config = nlohmann::json::parse(o.config_json());
    } catch (const nlohmann::json::exception& e) {
      FailInvalid("job " + job.id() + ": its config is not valid JSON: " + e.what());
    }
    if (!options.config.is_object()) FailInvalid("job " + job.id() + ": its config must be a JSON object");
  }
  if (!o.preset().empty()) options.preset = o.preset();
  if (o.has_iterations()) options.iterations = o.iterations();
  options.time_budget_s = o.time_budget_s();
  if (o.has_holdout()) options.holdout = o.holdout();
  options.seed = o.seed();
  options.force_static = o.force_static();
  options.threads = device.threads;
  if (job.has_checkpoint() && !job.checkpoint().sha256().empty()) {
    options.resume_from = (job_dir / "checkpoint" / job.checkpoint().path()).string();
  }
  return options;
}

}  // namespace endorecon::worker
