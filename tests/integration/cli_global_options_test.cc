// The CLI's global options (--server, --json, --timeout, and any added later) work after the
// subcommand too, as git, docker and kubectl users type them: `endorecon submit clip --json`.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "tests/integration/service_harness.h"

namespace endorecon::testing {
namespace {

TEST(CliGlobalOptionsTest, ServerAndTimeoutAfterTheSubcommand) {
  // An address nobody listens on: the call fails as unreachable (4), not as bad usage (2).
  const auto result =
      RunCliAsTyped({"list", "--server", "127.0.0.1:" + std::to_string(FreePort()), "--timeout", "1"});
  EXPECT_EQ(result.exit_code, 4) << result.err;
}

TEST(CliGlobalOptionsTest, JsonAfterTheSubcommand) {
  Cluster cluster;
  MakeClip(cluster.path("clip"));
  const auto submitted =
      RunCli(cluster.address(), {"submit", cluster.path("clip").string(), "--iterations", "5", "--json"});
  ASSERT_EQ(submitted.exit_code, 0) << submitted.err;
  const auto job = nlohmann::json::parse(submitted.out);
  ASSERT_TRUE(job.contains("id")) << submitted.out;
  const auto status = RunCli(cluster.address(), {"status", job["id"].get<std::string>(), "--json"});
  ASSERT_EQ(status.exit_code, 0) << status.err;
  EXPECT_EQ(nlohmann::json::parse(status.out)["id"], job["id"]);
}

TEST(CliGlobalOptionsTest, UnknownOptionsAreStillRefused) {
  const auto result = RunCliAsTyped({"list", "--no-such-option"});
  EXPECT_EQ(result.exit_code, 2);
  EXPECT_NE(result.err.find("--no-such-option"), std::string::npos) << result.err;
  const auto extra = RunCliAsTyped({"status", "abc", "def"});
  EXPECT_EQ(extra.exit_code, 2) << "a second job id is not taken";
}

}  // namespace
}  // namespace endorecon::testing
