#include "worker/runtime/prometheus_target_file.h"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <memory>
#include <nlohmann/json.hpp>

#include "tests/unit/temp_dir.h"

namespace endorecon::worker {
namespace {

TEST(PrometheusTargetFileTest, AWildcardBindIsScrapedByTheMachinesName) {
  EXPECT_EQ(ScrapeHost("0.0.0.0", "node17"), "node17");
  EXPECT_EQ(ScrapeHost("::", "node17"), "node17");
  EXPECT_EQ(ScrapeHost("10.1.0.17", "node17"), "10.1.0.17");
  EXPECT_EQ(ScrapeHost("fd00::17", "node17"), "[fd00::17]");
}

// The file Prometheus' file_sd_configs reads: one target, labelled with the worker; gone at the end.
TEST(PrometheusTargetFileTest, TheFileNamesTheTargetWhileTheWorkerServes) {
  testing::TempDir dir("targets");
  const auto file = dir / "node17-gpu0.json";
  {
    const PrometheusTargetFile target(file, "node17", 9466, "node17-slurm42-gpu0");
    const auto json = nlohmann::json::parse(testing::ReadBytes(file));
    ASSERT_TRUE(json.is_array());
    ASSERT_EQ(json.size(), 1u);
    EXPECT_EQ(json[0]["targets"], nlohmann::json::array({"node17:9466"}));
    EXPECT_EQ(json[0]["labels"]["endorecon_worker"], "node17-slurm42-gpu0");
  }
  EXPECT_FALSE(std::filesystem::exists(file));
  {
    // Under the worker's umask (077), every folder made, not the last alone, is open to Prometheus.
    const mode_t umask_before = ::umask(077);
    const PrometheusTargetFile target(dir / "made" / "deeper" / "t.json", "node17", 9466, "w");
    ::umask(umask_before);
    EXPECT_EQ(std::filesystem::status(dir / "made" / "deeper" / "t.json").permissions() &
                  std::filesystem::perms::all,
              std::filesystem::perms(0644))
        << "Prometheus runs as a user of its own";
    for (const auto& folder : {dir / "made", dir / "made" / "deeper"}) {
      EXPECT_EQ(std::filesystem::status(folder).permissions() & std::filesystem::perms::all,
                std::filesystem::perms(0755))
          << folder;
    }
  }
  // Two workers given one file: the first to stop leaves the second's target.
  {
    auto first = std::make_unique<PrometheusTargetFile>(file, "node17", 9466, "first");
    const PrometheusTargetFile second(file, "node18", 9466, "second");
    first.reset();
    EXPECT_NE(testing::ReadBytes(file).find("second"), std::string::npos) << "the second's target went";
  }
  EXPECT_FALSE(std::filesystem::exists(file));
  testing::WriteBytes(dir / "a-file", "");
  EXPECT_THROW(PrometheusTargetFile(dir / "a-file" / "t.json", "h", 1, "w"), std::exception)
      << "a folder that cannot be made";
}

}  // namespace
}  // namespace endorecon::worker
