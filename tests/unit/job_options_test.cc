#include "worker/runtime/job_options.h"

#include <gtest/gtest.h>

#include <string>

#include "common/error.h"

namespace endorecon::worker {
namespace {

v1::Job JobWith(const std::string& config_json) {
  v1::Job job;
  job.set_id("j42");
  auto* o = job.mutable_options();
  o->set_config_json(config_json);
  o->set_preset("paper");
  o->set_iterations(321);
  o->set_time_budget_s(45.5);
  o->set_holdout(0);
  o->set_seed(99);
  o->set_force_static(true);
  return job;
}

TEST(JobOptions, EveryOptionReachesTheEngine) {
  v1::Job job = JobWith(R"({"rays_per_batch": 64})");
  job.mutable_checkpoint()->set_path("checkpoint.bin");
  job.mutable_checkpoint()->set_sha256(std::string(64, 'a'));
  const Device device{"cpu1", "cpu", 3};
  const ReconstructOptions o = OptionsFor(job, "/work/j42", device);
  EXPECT_EQ(o.clip_dir, "/work/j42/clip");
  EXPECT_EQ(o.out_dir, "/work/j42/out");
  EXPECT_EQ(o.config, (nlohmann::json{{"rays_per_batch", 64}}));
  EXPECT_EQ(o.preset, "paper");
  EXPECT_EQ(o.iterations, 321);
  EXPECT_EQ(o.time_budget_s, 45.5);
  EXPECT_EQ(o.holdout, 0);
  EXPECT_EQ(o.seed, 99u);
  EXPECT_TRUE(o.force_static);
  EXPECT_EQ(o.threads, 3);
  EXPECT_EQ(o.resume_from, "/work/j42/checkpoint/checkpoint.bin");
}

TEST(JobOptions, UnsetOptionsKeepTheEngineDefaults) {
  v1::Job job;
  job.set_id("j1");
  const ReconstructOptions o = OptionsFor(job, "/w", Device{"cpu0", "cpu", 2});
  const ReconstructOptions defaults;
  EXPECT_EQ(o.preset, defaults.preset);
  EXPECT_EQ(o.iterations, defaults.iterations);
  EXPECT_EQ(o.holdout, defaults.holdout);
  EXPECT_TRUE(o.config.is_object() && o.config.empty());
  EXPECT_TRUE(o.resume_from.empty());
}

TEST(JobOptions, AConfigThatIsNotAJsonObjectFailsNamingTheJob) {
  for (const std::string bad : {"{not json", "[1, 2]", "\"text\""}) {
    try {
      OptionsFor(JobWith(bad), "/w", Device{"cpu0", "cpu", 1});
      ADD_FAILURE() << "accepted config " << bad;
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
      EXPECT_NE(std::string(e.what()).find("job j42"), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace endorecon::worker
