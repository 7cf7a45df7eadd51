// TLS and client certificates with real processes and certificates made by openssl at test time:
// what a client or worker that cannot prove itself (or cannot trust the server) gets, and what the
// server refuses to start with.
#include <grpcpp/generic/generic_stub.h>
#include <gtest/gtest.h>

#include <condition_variable>
#include <memory>
#include <mutex>
#include <optional>

#include "common/transport_security.h"
#include "tests/integration/audit_reader.h"
#include "tests/integration/service_harness.h"
#include "tests/integration/test_pki.h"

namespace endorecon::testing {
namespace fs = std::filesystem;
namespace {

class TlsTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    pki_dir_ = std::make_unique<TempDir>("pki");
    pki_ = std::make_unique<TestPki>(pki_dir_->path());
  }
  static void TearDownTestSuite() {
    pki_.reset();
    pki_dir_.reset();
  }

  // A server with TLS, client certificates required on the worker API, and tokens.
  void StartSecureServer() {
    cluster_ = std::make_unique<Cluster>(ServerTlsFlags(*pki_), false);
    admin_ = MakeCredentials(*cluster_, pki_->ca_cert.string(), "admin", "", "ops");
    worker_token_ = MakeCredentials(*cluster_, "", "worker", "", "node-1").token_file;
    cluster_->UseCredentials(admin_);
    cluster_->StartServer();
  }

  CliResult Cli(std::vector<std::string> flags, const std::vector<std::string>& args) {
    flags.insert(flags.end(), args.begin(), args.end());
    return RunCli(cluster_->address(), flags);
  }

  // A server started in `dir` with this certificate and key, run until it exits; `out` holds its
  // stdout and stderr.
  static CliResult StartServerWith(const TempDir& dir, const fs::path& cert, const fs::path& key) {
    return Together(
        RunCommand({BuiltBinary("server/endorecon-server"), "--listen",
                    "127.0.0.1:" + std::to_string(FreePort()), "--data-dir", (dir / "data").string(),
                    "--metrics-port", "-1", "--tls-cert", cert.string(), "--tls-key", key.string()}));
  }
  // A worker given this certificate and key, run until it exits (its metrics on a port it picks).
  static CliResult StartWorkerWith(const fs::path& cert, const fs::path& key) {
    return Together(
        RunCommand({BuiltBinary("worker/runtime/endorecon-worker"), "serve", "--server",
                    "127.0.0.1:" + std::to_string(FreePort()), "--devices", "cpu", "--metrics-port", "0",
                    "--ca", pki_->ca_cert.string(), "--tls-cert", cert.string(), "--tls-key", key.string()}));
  }
  static CliResult Together(CliResult result) {
    result.out += result.err;
    return result;
  }

  static std::unique_ptr<TempDir> pki_dir_;
  static std::unique_ptr<TestPki> pki_;
  std::unique_ptr<Cluster> cluster_;
  ClientCredentials admin_;
  std::string worker_token_;
};

std::unique_ptr<TempDir> TlsTest::pki_dir_;
std::unique_ptr<TestPki> TlsTest::pki_;

// grpc.health.v1.Health/Check over plaintext, without generated stubs: the empty request, and the
// raw response bytes (08 01 is status SERVING).
std::string HealthCheckBytes(const std::string& address) {
  grpc::GenericStub stub(OpenChannel(address));
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(5));
  grpc::Slice empty("", 0);
  grpc::ByteBuffer request(&empty, 1), response;
  std::mutex mutex;
  std::condition_variable done;
  std::optional<grpc::Status> status;
  stub.UnaryCall(&context, "/grpc.health.v1.Health/Check", grpc::StubOptions(), &request, &response,
                 [&](grpc::Status result) {
                   std::lock_guard lock(mutex);
                   status = result;
                   done.notify_all();
                 });
  std::unique_lock lock(mutex);
  done.wait(lock, [&] { return status.has_value(); });
  if (!status->ok()) return "error " + status->error_message();
  std::vector<grpc::Slice> slices;
  (void)response.Dump(&slices);
  std::string bytes;
  for (const auto& slice : slices) bytes.append(reinterpret_cast<const char*>(slice.begin()), slice.size());
  return bytes;
}

TEST_F(TlsTest, ClientsThatCannotTrustTheServerOrSpeakPlaintextGetNothing) {
  StartSecureServer();
  const auto trusted = Cli(admin_.CliFlags(), {"list"});
  ASSERT_EQ(trusted.exit_code, 0) << trusted.err;

  const auto plaintext = Cli({"--token-file", admin_.token_file, "--timeout", "2"}, {"list"});
  EXPECT_EQ(plaintext.exit_code, 4) << plaintext.err;
  EXPECT_NE(plaintext.err.find("--ca"), std::string::npos) << plaintext.err;
  // Where nothing listens, TLS is not the question.
  const auto nobody = RunCli("127.0.0.1:" + std::to_string(FreePort()), {"--timeout", "2", "list"});
  EXPECT_EQ(nobody.exit_code, 4) << nobody.err;
  EXPECT_NE(nobody.err.find("nothing listens at"), std::string::npos) << nobody.err;
  EXPECT_EQ(nobody.err.find("--ca"), std::string::npos) << nobody.err;

  const auto untrusted = Cli(
      {"--ca", pki_->rogue_ca_cert.string(), "--token-file", admin_.token_file, "--timeout", "2"}, {"list"});
  EXPECT_EQ(untrusted.exit_code, 4) << untrusted.err;
  EXPECT_NE(untrusted.err.find("UNAVAILABLE"), std::string::npos) << untrusted.err;
  // It says which side's setting is wrong, and gRPC's own log lines stay off the terminal.
  EXPECT_NE(untrusted.err.find("the server's certificate does not verify against --ca " +
                               pki_->rogue_ca_cert.string()),
            std::string::npos)
      << untrusted.err;
  EXPECT_EQ(untrusted.err.find("ssl_transport_security.cc"), std::string::npos) << untrusted.err;
}

TEST_F(TlsTest, TheHealthPortAnswersInPlaintextBesideTheTlsPort) {
  TempDir dir("health");
  const int port = FreePort(), health = FreePort();
  Process server(
      {BuiltBinary("server/endorecon-server"), "--listen", "127.0.0.1:" + std::to_string(port), "--data-dir",
       (dir / "data").string(), "--metrics-port", "-1", "--tls-cert", pki_->server_cert.string(), "--tls-key",
       pki_->server_key.string(), "--health-listen", "127.0.0.1:" + std::to_string(health)},
      dir / "server.log");
  ASSERT_TRUE(WaitUntil([&] { return PortOpen(health); }, std::chrono::seconds(20))) << server.Log();
  EXPECT_TRUE(WaitUntil([&] { return HealthCheckBytes("127.0.0.1:" + std::to_string(health)) == "\x08\x01"; },
                        std::chrono::seconds(10)));
  // The API is not there: only the health service answers on that port.
  const auto api = RunCli("127.0.0.1:" + std::to_string(health), {"--timeout", "2", "list"});
  EXPECT_EQ(api.exit_code, 1) << api.err;  // UNIMPLEMENTED
  // ... and the CLI says which port it reached (it said "INTERNAL: list: " and nothing more).
  EXPECT_NE(api.err.find("--health-listen"), std::string::npos) << api.err;
  // With --ca, as a secured deployment's CLI has it, the plaintext port is named as such.
  const auto tls = RunCli("127.0.0.1:" + std::to_string(health),
                          {"--ca", pki_->ca_cert.string(), "--timeout", "2", "list"});
  EXPECT_EQ(tls.exit_code, 4) << tls.err;
  EXPECT_NE(tls.err.find("the address does not answer in TLS"), std::string::npos) << tls.err;
}

// An expired certificate started and listened without a word, and every client then failed with a
// bare "certificate verify failed" (found 2026-12-05): it is refused at start, as a worker's own.
TEST_F(TlsTest, AnExpiredCertificateIsRefusedAtStart) {
  TempDir dir("expired");
  const auto server = StartServerWith(dir, pki_->expired_cert, pki_->expired_key);
  EXPECT_EQ(server.exit_code, 2) << server.out;
  EXPECT_NE(server.out.find("--tls-cert " + pki_->expired_cert.string() + " expired on "), std::string::npos)
      << server.out;
  const auto worker = StartWorkerWith(pki_->expired_cert, pki_->expired_key);
  EXPECT_EQ(worker.exit_code, 2) << worker.out;
  EXPECT_NE(worker.out.find("expired on "), std::string::npos) << worker.out;
}

// A certificate made for the other side of TLS: a server given a worker's (clientAuth only) started,
// and every client failed "does not verify against --ca: is it signed by that CA, and valid now?",
// which it was (found 2026-12-07). Both are refused at start, naming what is left out.
TEST_F(TlsTest, ACertificateForTheOtherSideIsRefusedAtStart) {
  TempDir dir("purpose");
  const auto server = StartServerWith(dir, pki_->worker_cert, pki_->worker_key);
  EXPECT_EQ(server.exit_code, 2) << server.out;
  EXPECT_NE(server.out.find("--tls-cert " + pki_->worker_cert.string() +
                            " is not made for a TLS server: its extendedKeyUsage (or keyUsage) leaves out "
                            "serverAuth, so clients refuse it; is it a worker's certificate?"),
            std::string::npos)
      << server.out;
  const auto worker = StartWorkerWith(pki_->server_cert, pki_->server_key);
  EXPECT_EQ(worker.exit_code, 2) << worker.out;
  EXPECT_NE(worker.out.find("is not made for a TLS client: its extendedKeyUsage (or keyUsage) leaves out "
                            "clientAuth, so the server refuses it; is it the server's certificate?"),
            std::string::npos)
      << worker.out;
}

TEST_F(TlsTest, WorkersWithoutAClientCertificateOrWithAClientTokenLeaseNothing) {
  StartSecureServer();
  MakeClip(cluster_->path("clip"));
  const auto id = cluster_->Submit(cluster_->path("clip"), {"--iterations", "5"});

  auto& no_certificate =
      cluster_->StartWorker("w-no-cert", {"--ca", pki_->ca_cert.string(), "--token-file", worker_token_});
  EXPECT_NE(no_certificate.Wait(), 0);
  EXPECT_NE(no_certificate.Log().find("client certificate"), std::string::npos) << no_certificate.Log();

  // A certificate from a CA the server does not trust fails the handshake: the worker never gets in.
  auto& rogue = cluster_->StartWorker(
      "w-rogue", {"--ca", pki_->ca_cert.string(), "--tls-cert", pki_->rogue_cert.string(), "--tls-key",
                  pki_->rogue_key.string(), "--token-file", worker_token_, "--timeout", "2"});
  std::this_thread::sleep_for(std::chrono::seconds(3));
  rogue.Signal(SIGTERM);
  rogue.Wait();
  EXPECT_NE(rogue.Log().find("cannot register"), std::string::npos) << rogue.Log();
  // Said once in its 3 s, not once a retry (a line a second for as long as it ran, until 2026-12-05).
  const std::string rogue_log = rogue.Log();
  std::size_t said = 0;
  for (auto at = rogue_log.find("cannot register"); at != std::string::npos;
       at = rogue_log.find("cannot register", at + 1)) {
    ++said;
  }
  EXPECT_EQ(said, 1u) << rogue_log;
  // Stopped before it ever registered, it does not say it was serving (it did, found 2026-12-05).
  EXPECT_EQ(rogue_log.find("serving"), std::string::npos) << rogue_log;
  EXPECT_NE(rogue_log.find("stopped before it could register"), std::string::npos) << rogue_log;
  // The server says so too, once in those 3 s, and counts each failed handshake for the alerts: it
  // fails before any call, so it wrote a bare gRPC line a retry and nothing counted it (found 2026-12-07).
  const auto server_log = cluster_->ServerLog();
  EXPECT_NE(server_log.find("grpc: Handshake failed"), std::string::npos) << server_log;
  EXPECT_NE(server_log.find("endorecon_tls_handshake_failures_total counts them"), std::string::npos)
      << server_log;
  const auto metrics = Capture(
      "curl -s --max-time 5 http://127.0.0.1:" + std::to_string(cluster_->metrics_port()) + "/metrics");
  const auto counted = metrics.find("\nendorecon_tls_handshake_failures_total ");
  ASSERT_NE(counted, std::string::npos) << metrics;
  EXPECT_GE(std::stod(metrics.substr(counted + 40)), 2.0) << "a handshake a retry";

  // A worker whose --ca does not verify the server: gRPC's own lines go to its log paced, not two bare
  // lines a retry on its stderr (found 2026-12-07).
  auto& other_ca =
      cluster_->StartWorker("w-other-ca", {"--ca", pki_->rogue_ca_cert.string(), "--tls-cert",
                                           pki_->worker_cert.string(), "--tls-key", pki_->worker_key.string(),
                                           "--token-file", worker_token_, "--timeout", "1"});
  std::this_thread::sleep_for(std::chrono::seconds(4));
  other_ca.Signal(SIGTERM);
  other_ca.Wait();
  const std::string other_log = other_ca.Log();
  EXPECT_NE(other_log.find("does not verify"), std::string::npos) << other_log;
  EXPECT_EQ(other_log.find("ssl_transport_security.cc"), std::string::npos) << other_log;
  std::size_t handshakes = 0;
  for (auto at = other_log.find("Handshake failed"); at != std::string::npos;
       at = other_log.find("Handshake failed", at + 1)) {
    ++handshakes;
  }
  EXPECT_LE(handshakes, 2u) << other_log;

  // Plaintext to the TLS port: the log says to give --ca, as the CLI does (it said nothing).
  auto& plaintext = cluster_->StartWorker("w-plaintext", {"--token-file", worker_token_, "--timeout", "2"});
  ASSERT_TRUE(WaitUntil([&] { return plaintext.Log().find("cannot register") != std::string::npos; },
                        std::chrono::seconds(20)))
      << plaintext.Log();
  plaintext.Signal(SIGTERM);
  plaintext.Wait();
  EXPECT_NE(plaintext.Log().find("if it serves TLS, give --ca FILE"), std::string::npos) << plaintext.Log();

  auto& client_token = cluster_->StartWorker("w-client-token", WorkerTlsFlags(*pki_, admin_.token_file));
  EXPECT_EQ(client_token.Wait(), 11)
      << "PERMISSION_DENIED: not restarted by systemd (RestartPreventExitStatus)";
  EXPECT_NE(client_token.Log().find("PERMISSION_DENIED"), std::string::npos) << client_token.Log();

  EXPECT_EQ(cluster_->Job(id).state(), v1::QUEUED);
  const auto audit = AuditLines(cluster_->data_dir() / "audit.jsonl");
  EXPECT_EQ(AuditFind(audit, "Register", "UNAUTHENTICATED").size(), 1u);
  EXPECT_TRUE(AuditFind(audit, "Register", "OK").empty());
  const auto denied = AuditFind(audit, "Register", "PERMISSION_DENIED", "ops");
  ASSERT_EQ(denied.size(), 1u);
  EXPECT_EQ(denied[0].value("certificate", ""), "worker-1");
}

TEST_F(TlsTest, TheServerRefusesPlaintextBeyondLoopbackAndReadableKeys) {
  TempDir dir("refusals");
  const std::string server = BuiltBinary("server/endorecon-server");
  Process exposed({server, "--listen", "0.0.0.0:" + std::to_string(FreePort()), "--data-dir",
                   (dir / "d").string(), "--metrics-port", "-1"},
                  dir / "exposed.log");
  EXPECT_EQ(exposed.Wait(), 2);
  EXPECT_NE(exposed.Log().find("without TLS"), std::string::npos) << exposed.Log();

  const auto readable_key = dir / "readable.key";
  fs::copy_file(pki_->server_key, readable_key);
  fs::permissions(readable_key, fs::perms::others_read, fs::perm_options::add);
  Process leaky(
      {server, "--listen", "127.0.0.1:" + std::to_string(FreePort()), "--data-dir", (dir / "d").string(),
       "--metrics-port", "-1", "--tls-cert", pki_->server_cert.string(), "--tls-key", readable_key.string()},
      dir / "leaky.log");
  EXPECT_EQ(leaky.Wait(), 2);
  EXPECT_NE(leaky.Log().find("chmod 600 "), std::string::npos) << leaky.Log();

  // --insecure serves beyond loopback in plaintext, and says so loudly.
  const int insecure_port = FreePort();
  Process insecure({server, "--listen", "0.0.0.0:" + std::to_string(insecure_port), "--data-dir",
                    (dir / "d").string(), "--metrics-port", "-1", "--insecure"},
                   dir / "insecure.log");
  EXPECT_TRUE(WaitUntil([&] { return PortOpen(insecure_port); }, std::chrono::seconds(20))) << insecure.Log();
  insecure.Signal(SIGTERM);
  EXPECT_EQ(insecure.Wait(), 0);
  EXPECT_NE(insecure.Log().find("critical"), std::string::npos) << insecure.Log();
  EXPECT_NE(insecure.Log().find("WITHOUT TLS"), std::string::npos) << insecure.Log();

  // Workers and clients refuse readable secrets too.
  const auto readable_token = dir / "readable.token";
  WriteBytes(readable_token, "endorecon.0.0\n");
  fs::permissions(readable_token, fs::perms::others_read, fs::perm_options::add);
  const auto cli = RunCli("127.0.0.1:1", {"--token-file", readable_token.string(), "list"});
  EXPECT_EQ(cli.exit_code, 2) << cli.err;
  EXPECT_NE(cli.err.find("others may access it"), std::string::npos) << cli.err;

  // A certificate with another certificate's key is refused at start, naming both files: a worker
  // retried "empty address list" once a second for good, and the server said the port might be
  // taken (found 2026-12-05).
  Process mismatched({server, "--listen", "127.0.0.1:" + std::to_string(FreePort()), "--data-dir",
                      (dir / "d").string(), "--metrics-port", "-1", "--tls-cert", pki_->server_cert.string(),
                      "--tls-key", pki_->worker_key.string()},
                     dir / "mismatched.log");
  EXPECT_EQ(mismatched.Wait(), 2);
  EXPECT_NE(mismatched.Log().find("are not a pair: the key belongs to another certificate"),
            std::string::npos)
      << mismatched.Log();
  Process worker({BuiltBinary("worker/runtime/endorecon-worker"), "serve", "--server", "127.0.0.1:1", "--ca",
                  pki_->ca_cert.string(), "--tls-cert", pki_->worker_cert.string(), "--tls-key",
                  pki_->server_key.string(), "--metrics-port", "-1", "--work-dir", (dir / "w").string()},
                 dir / "worker.log");
  EXPECT_EQ(worker.Wait(), 2);
  EXPECT_NE(worker.Log().find("--tls-cert " + pki_->worker_cert.string() + " and --tls-key"),
            std::string::npos)
      << worker.Log();
}

}  // namespace
}  // namespace endorecon::testing
