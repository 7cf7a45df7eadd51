// Bad DICOM input is refused with what and where: at submit (an unknown PACS name, a malformed
// Study UID) or when the worker prepares the clip (a file that is not DICOM); nothing else is lost.
#include <gtest/gtest.h>

#include "tests/integration/service_harness.h"

namespace endorecon::testing {
namespace {

TEST(BadDicomInputTest, RefusedAtSubmitOrAtPreparation) {
  Cluster cluster;
  cluster.StartWorker("w1");
  WriteBytes(cluster.path("recording.dcm"), std::string(1000, 'x'));
  const auto bad = RunCli(cluster.address(), {"submit", cluster.path("recording.dcm").string(), "--wait"});
  EXPECT_EQ(bad.exit_code, 5) << bad.out << bad.err;
  EXPECT_NE(bad.out.find("recording.dcm: not a DICOM file (no \"DICM\" at byte 128)"), std::string::npos)
      << bad.out;

  const auto unknown = RunCli(cluster.address(), {"submit", "--pacs", "nowhere", "--study", "1.2.3"});
  EXPECT_EQ(unknown.exit_code, 3) << unknown.err;
  EXPECT_NE(unknown.err.find("no PACS named 'nowhere' is configured on the server"), std::string::npos)
      << unknown.err;

  // The worker is still there for the next job.
  MakeClip(cluster.path("clip"));
  const auto good =
      RunCli(cluster.address(), {"submit", cluster.path("clip").string(), "--iterations", "10", "--wait"});
  EXPECT_EQ(good.exit_code, 0) << good.out << good.err;
}

}  // namespace
}  // namespace endorecon::testing
