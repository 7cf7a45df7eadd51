// One whole job the way a hospital deploys it: the server on TLS, the worker with a client
// certificate (mTLS) and a worker token, the user with a client token; submit, watch, fetch, and
// the audit log telling who did what.
#include <gtest/gtest.h>

#include "common/sha256.h"
#include "tests/integration/audit_reader.h"
#include "tests/integration/service_harness.h"
#include "tests/integration/test_pki.h"

namespace endorecon::testing {
namespace {

TEST(SecureJobTest, TlsMtlsAndTokensEndToEnd) {
  TempDir pki_dir("pki");
  const TestPki pki(pki_dir.path());
  Cluster cluster(ServerTlsFlags(pki), false);
  const auto alice = MakeCredentials(cluster, pki.ca_cert.string(), "client", "radiology", "alice");
  const auto worker = MakeCredentials(cluster, "", "worker", "", "gpu-node-7");
  cluster.UseCredentials(MakeCredentials(cluster, pki.ca_cert.string(), "admin", "", "ops"));
  cluster.StartServer();
  cluster.StartWorker("w1", WorkerTlsFlags(pki, worker.token_file));
  MakeClip(cluster.path("clip"));

  auto args = alice.CliFlags();
  args.insert(args.end(), {"submit", cluster.path("clip").string(), "--iterations", "30", "--wait"});
  const auto submitted = RunCli(cluster.address(), args);
  ASSERT_EQ(submitted.exit_code, 0) << submitted.err << submitted.out << cluster.ServerLog();
  const auto id = submitted.out.substr(submitted.out.find("job ") + 4, 12);
  const auto job = cluster.Job(id);
  ASSERT_EQ(job.state(), v1::SUCCEEDED);
  EXPECT_EQ(job.tenant(), "radiology");
  EXPECT_EQ(job.worker_id(), "w1");

  args = alice.CliFlags();
  args.insert(args.end(), {"fetch", id, "-o", cluster.path("results").string()});
  const auto fetched = RunCli(cluster.address(), args);
  ASSERT_EQ(fetched.exit_code, 0) << fetched.err;
  for (const auto& file : job.result().files())
    EXPECT_EQ(Sha256File(cluster.path("results") / file.path()), file.sha256()) << file.path();

  const auto audit = AuditLines(cluster.data_dir() / "audit.jsonl");
  EXPECT_EQ(AuditFind(audit, "Upload", "OK", "alice").size(), 1u);
  const auto submit = AuditFind(audit, "Submit", "OK", "alice", id);
  ASSERT_EQ(submit.size(), 1u);
  EXPECT_EQ(submit[0]["tenant"], "radiology");
  EXPECT_EQ(submit[0]["role"], "client");
  const auto lease = AuditFind(audit, "Lease", "OK", "gpu-node-7", id);
  ASSERT_EQ(lease.size(), 1u);
  EXPECT_EQ(lease[0]["certificate"], "worker-1");
  EXPECT_EQ(AuditFind(audit, "Complete", "OK", "gpu-node-7", id).size(), 1u);
  EXPECT_GE(AuditFind(audit, "PutBlobs", "OK", "gpu-node-7").size(), 1u);
}

}  // namespace
}  // namespace endorecon::testing
