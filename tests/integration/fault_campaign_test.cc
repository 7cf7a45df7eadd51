// The kill campaign at CI size (bench/fault_campaign --kills 10: every phase at least once, victims
// restarted): nothing submitted is lost or corrupted. The 100-kill figures are in docs/benchmarks.md.
#include <gtest/gtest.h>

#include "tests/integration/sanitizer_build.h"
#include "tests/integration/service_harness.h"

namespace endorecon::testing {
namespace {

TEST(FaultCampaignTest, TenKillsLoseNothing) {
  TempDir dir("campaign");
  // An instrumented build trains and serves several times slower: its jobs get as much longer to drain.
  Process campaign(
      {BuiltBinary("bench/fault_campaign"), "--kills", "10", "--clients", "2", "--iterations", "80", "--dir",
       (dir / "run").string(), "--phase-wait", "40", "--drain", std::to_string(120 * kSlowdown)},
      dir / "out");
  const int code = campaign.Wait();
  const std::string out = campaign.Log();
  EXPECT_EQ(code, 0) << out;
  const auto last = out.rfind("lost=");
  ASSERT_NE(last, std::string::npos) << out;
  EXPECT_EQ(out.substr(last, 18), "lost=0 corrupt=0 s") << out;
}

}  // namespace
}  // namespace endorecon::testing
