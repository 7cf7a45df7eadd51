#include "worker/engine/run_config.h"

#include <gtest/gtest.h>

#include <string>

#include "common/error.h"

namespace endorecon {
namespace {

TEST(RunConfig, TheOptionsGoOverThePreset) {
  ReconstructOptions options;
  options.preset = "paper";
  options.config = {{"rays_per_batch", 64}, {"field", {{"grids", {{"levels", 4}}}}}};
  options.iterations = 12;
  options.holdout = 0;
  const train::TrainConfig config = ResolveConfig(options);
  EXPECT_EQ(config.preset, "paper");
  EXPECT_EQ(config.rays_per_batch, 64);
  EXPECT_EQ(config.field.grids.levels, 4);
  EXPECT_EQ(config.field.grids.features, 8);  // the paper's, untouched
  EXPECT_EQ(config.iterations, 12);
  EXPECT_EQ(config.holdout, 0);
}

TEST(RunConfig, WithABudgetTheIterationCountIsACapOnlyWhenGiven) {
  ReconstructOptions options;
  options.time_budget_s = 120;
  EXPECT_EQ(ResolveConfig(options).iterations, 0) << "no cap: the schedule runs on time";
  options.iterations = 500;
  EXPECT_EQ(ResolveConfig(options).iterations, 500);
  options = {};
  EXPECT_EQ(ResolveConfig(options).iterations, train::TrainConfig::Preset("cpu").iterations);
  options.config = {{"iterations", 0}};  // e.g. a budgeted run's configuration, run without a budget
  EXPECT_EQ(ResolveConfig(options).iterations, train::TrainConfig::Preset("cpu").iterations);
}

TEST(RunConfig, AConfigThatIsNoObjectOrHasAnUnknownKeyIsRefused) {
  ReconstructOptions options;
  options.config = nlohmann::json::array({1, 2});
  try {
    ResolveConfig(options);
    FAIL() << "took an array";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
    EXPECT_NE(std::string(e.what()).find("must be a JSON object"), std::string::npos) << e.what();
  }
  options.config = {{"rays_per_bacth", 64}};
  try {
    ResolveConfig(options);
    FAIL() << "took an unknown key";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("rays_per_bacth"), std::string::npos) << e.what();
  }
}

TEST(RunConfig, EveryKthFrameIsHeldOutButNeverTheFirst) {
  const FrameSplit split = SplitFrames(10, 4);
  EXPECT_EQ(split.heldout, (std::vector<int>{3, 7}));
  EXPECT_EQ(split.train, (std::vector<int>{0, 1, 2, 4, 5, 6, 8, 9}));
  EXPECT_TRUE(SplitFrames(5, 0).heldout.empty());
  EXPECT_TRUE(SplitFrames(5, 1).heldout.empty());
}

// Steps and renders go to one device; one that cannot run is refused naming it (this machine has no
// CUDA device 99, with or without a CUDA build), never replaced by the CPU.
TEST(RunConfig, ADeviceThatCannotRunIsRefusedForStepsAndRendersNamingIt) {
  const DeviceBackends cpu = BackendsFor("cpu");
  EXPECT_TRUE(cpu.step && cpu.render);
  for (const std::string bad : {"cuda:99", "gpu", "cuda:", "cpu:1"}) {
    try {
      BackendsFor(bad);
      ADD_FAILURE() << "accepted device " << bad;
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument) << bad;
      EXPECT_NE(std::string(e.what()).find(bad), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace endorecon
