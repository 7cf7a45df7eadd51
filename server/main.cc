// endorecon-server: the job API (clients), the worker API (workers pull jobs), a durable job store,
// a content-addressed blob store, Prometheus metrics and grpc.health.v1. See docs/operations.md.
// Subcommands: `token create|list|revoke` and `retention --dry-run` (server/commands.h).
#include <grpcpp/grpcpp.h>
#include <grpcpp/health_check_service_interface.h>
#include <grpcpp/resource_quota.h>
#include <signal.h>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <atomic>
#include <filesystem>
#include <thread>

#include "common/cli_checks.h"
#include "common/cli_usage.h"
#include "common/dicom/peer.h"
#include "common/dicom/storage_scp.h"
#include "common/dicom/uid.h"
#include "common/error.h"
#include "common/folder_lock.h"
#include "common/grpc_log.h"
#include "common/job_bounds.h"
#include "common/metrics_exposer.h"
#include "common/private_folder.h"
#include "common/transport_security.h"
#include "endorecon_version.h"
#include "server/call_guard.h"
#include "server/commands.h"
#include "server/data_folder.h"
#include "server/dicom_retriever.h"
#include "server/dicom_sender.h"
#include "server/health_port.h"
#include "server/idle_trim.h"
#include "server/job_service.h"
#include "server/port_probe.h"
#include "server/worker_service.h"

namespace {

using namespace endorecon;
using namespace endorecon::server;

struct ServerFlags {
  std::string listen = "127.0.0.1:50051";
  std::string data_dir = "endorecon-data";
  int metrics_port = 9464;
  std::string metrics_host = "127.0.0.1";
  std::int64_t max_upload_bytes = std::int64_t{20} << 30;
  std::int64_t min_free_bytes = std::int64_t{256} << 20;
  double stall_timeout_s = 60;
  int max_threads = 512;
  int max_uploads = 16;
  int max_attempts = 3;
  std::int64_t lease_ttl_ms = 30000;
  std::int64_t heartbeat_ms = 2000;
  // Hospital imaging (docs/operations.md, "Hospital imaging").
  DicomSettings dicom;
  std::vector<std::string> pacs;
  // Security and operations (docs/operations.md, "Securing a deployment").
  ServerSecurity tls;
  bool insecure = false;
  bool require_tokens = false;
  std::string health_listen;
  std::string audit_log;
  Quota tenant_quota;
  std::string quotas_file;
  double retention_days = 0;
  double retention_check_s = 3600;
  double orphan_hours = 24;
};

std::string HostOf(const std::string& address) {
  if (!address.empty() && address.front() == '[') return address.substr(0, address.find(']') + 1);
  return address.substr(0, address.rfind(':'));
}

// The storage SCP, when --dicom-listen asks for one; C-MOVE progress goes to `retriever`.
std::unique_ptr<dicom::StorageScp> StartStorageScp(const ServerFlags& flags,
                                                   const std::filesystem::path& folder,
                                                   const std::vector<std::string>& calling_ae_titles,
                                                   DicomRetriever*& retriever) {
  if (flags.dicom.listen.empty()) return nullptr;
  dicom::StorageScpSettings settings;
  settings.ae_title = flags.dicom.ae_title;
  // HOST:PORT with a port of 1-65535 (the flag's check).
  settings.port = std::stoi(flags.dicom.listen.substr(flags.dicom.listen.rfind(':') + 1));
  settings.folder = folder;
  settings.calling_ae_titles = calling_ae_titles;
  // What an earlier run left (a C-MOVE cut short by a stop) is no study any retrieval awaits now.
  std::error_code ignored;
  std::filesystem::remove_all(folder, ignored);
  std::unique_ptr<dicom::StorageScp> scp;
  try {
    scp = std::make_unique<dicom::StorageScp>(
        settings,
        [&retriever](const std::string& study, const std::filesystem::path&, std::int64_t bytes) {
          if (retriever != nullptr) retriever->Received(study, bytes);
        },
        [&retriever](const std::string& study) { return retriever != nullptr && retriever->Awaits(study); });
  } catch (const Error& e) {  // a port taken: said with the option that chose it
    Fail(e.code(), "--dicom-listen " + flags.dicom.listen + ": " + e.what());
  }
  spdlog::info(
      "DICOM storage SCP {} listening on port {} (every interface; admits the configured PACS' AE titles)",
      settings.ae_title, settings.port);
  return scp;
}

// Blocks SIGINT/SIGTERM in every thread; one thread waits for them and shuts the server down.
sigset_t BlockStopSignals() {
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGINT);
  sigaddset(&signals, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);
  return signals;
}

// Refuses a listener that would carry patient data in the clear beyond this machine.
void CheckExposure(const ServerFlags& flags) {
  if (IsLoopbackAddress(flags.listen) || flags.tls.tls()) return;
  if (!flags.insecure) {
    FailInvalid(
        "refusing to listen on " + flags.listen +
        " without TLS: pass --tls-cert and --tls-key (docs/operations.md, \"Securing a deployment\"), "
        "or --insecure on a network you trust entirely");
  }
  spdlog::critical(
      "--insecure: serving {} WITHOUT TLS. Clips, results and tokens cross the network in the clear; anyone "
      "on "
      "the path can read them. Use TLS (--tls-cert, --tls-key) for anything but an isolated test network.",
      flags.listen);
}

int Run(const ServerFlags& flags) {
  const sigset_t stop_signals = BlockStopSignals();
  CheckExposure(flags);
  dicom::CheckAeTitle(flags.dicom.ae_title, "--ae-title");
  if (!flags.dicom.uid_root.empty()) dicom::NewUid(flags.dicom.uid_root);  // refuses a malformed root now
  const auto credentials = ServerCredentials(flags.tls);
  CheckPortFree(flags.listen);  // before the data folder is opened and its running jobs requeued
  // Every flag's file and port is checked before the data folder is made: a refused start leaves no
  // empty job store behind (found 2026-12-07).
  TenantQuotas quotas(flags.tenant_quota, flags.quotas_file);
  const PacsDirectory pacs(flags.pacs);
  Metrics metrics(flags.metrics_port >= 0 ? MetricsAddress(flags.metrics_host, flags.metrics_port) : "");
  const std::filesystem::path data_dir = flags.data_dir;
  RefuseAStoreBesideIt(data_dir);
  RefuseRootInAnotherUsersFolder(data_dir, "endorecon-server");
  if (MakePrivateFolder(data_dir)) {
    spdlog::warn(
        "{} is open to its group or others, and holds patient data: make it its owner's alone "
        "(chmod 700)",
        data_dir.string());
  }
  const FolderLock lock(data_dir, "server.lock", "endorecon-server", "data folder");
  RefuseBlobsWithoutTheirStore(data_dir);
  // The blob folders before the store: a start refused for them made an empty store, and the next
  // start (blobs/ chowned back) took every blob for no job's (found 2026-12-07).
  BlobStore blobs(data_dir);
  JobStore store(data_dir / "jobs.sqlite");
  // A start on a disk already below the reserve (a restart after the job store met a full disk):
  // said at once, not at the first refused upload or failed commit (found 2026-12-07).
  if (std::error_code error; flags.min_free_bytes > 0) {
    const auto space = std::filesystem::space(data_dir, error);
    if (!error && static_cast<std::int64_t>(space.available) < flags.min_free_bytes) {
      spdlog::warn(
          "the data disk of {} has {} bytes free, less than --min-free-bytes {}: clients' uploads are "
          "refused and the job store may fail to commit until space is freed there",
          data_dir.string(), space.available, flags.min_free_bytes);
    }
  }
  Scheduler scheduler;
  LeaseTable leases(std::chrono::milliseconds(flags.lease_ttl_ms));
  WorkerRegistry workers(std::chrono::milliseconds(flags.lease_ttl_ms), data_dir / "drains.json");
  WatchHub hub;
  // A commit slower than this is logged: a writing call waited for it (the disk's fsync, usually).
  constexpr double kSlowCommitSeconds = 0.1;
  store.SetCommitObserver([&metrics](double seconds, std::size_t writes) {
    metrics.StoreCommitted(seconds);
    if (seconds >= kSlowCommitSeconds) {
      spdlog::warn("job store: a commit of {} write(s) took {:.0f} ms; the calls that wrote waited for it",
                   writes, seconds * 1000);
    }
  });
  AuditLog audit(flags.audit_log.empty() ? data_dir / "audit.jsonl" : std::filesystem::path(flags.audit_log));
  audit.SetFailureObserver([&metrics] { metrics.AuditWriteFailed(); });
  const GrpcLogRoute grpc_log(
      "a client or worker whose certificate this server does not trust, or plaintext to the TLS port: "
      "endorecon_tls_handshake_failures_total counts them",
      [&metrics] { metrics.TlsHandshakeFailed(); });
  CallGuard guard(TokenStore::PathIn(data_dir), !flags.tls.client_ca_file.empty(), audit, metrics,
                  flags.require_tokens);
  spdlog::info("tenant quotas: {}", quotas.Describe());  // an admin checks what is in force
  JobCoordinator coordinator({store, blobs, scheduler, leases, workers, hub, metrics}, flags.max_attempts,
                             std::move(quotas));
  for (const auto& name : pacs.Names()) metrics.DeclarePacs(name);
  DicomRetriever* retriever_for_scp = nullptr;
  std::vector<std::string> pacs_ae_titles;
  for (const auto& name : pacs.Names()) pacs_ae_titles.push_back(pacs.Find(name).ae_title);
  const auto scp = StartStorageScp(flags, data_dir / "dicom-incoming", pacs_ae_titles, retriever_for_scp);
  const PacsAudit pacs_audit = [&guard](const std::string& method, const std::string& job_id,
                                        const std::string& outcome, const std::string& pacs_name) {
    guard.RecordServerAction(method, job_id, outcome, pacs_name);
  };
  DicomRetriever retriever(coordinator, blobs, pacs, flags.dicom, metrics, data_dir / "retrievals", scp.get(),
                           pacs_audit);
  retriever_for_scp = &retriever;
  DicomSender sender(coordinator, blobs, pacs, flags.dicom, metrics, pacs_audit);
  coordinator.SetDicomHooks({&pacs, flags.dicom.uid_root,
                             [&](const std::string& id) { retriever.Retrieve(id); },
                             [&](const std::string& id) { sender.Send(id); }});
  for (const auto& name : pacs.Names()) {
    spdlog::info("PACS {} = {} (this server calls as {})", name, dicom::PeerText(pacs.Find(name)),
                 flags.dicom.ae_title);
  }
  coordinator.KeepUploadsIn(data_dir / "uploads.json");
  coordinator.KeepOrphansIn(data_dir / "orphans.json");
  coordinator.SetTokenRevokedAt([&guard](const std::string& name) { return guard.TokenRevokedAt(name); });
  coordinator.Recover();
  IdleTrim idle_trim;
  UploadReceiver uploads(blobs, flags.max_upload_bytes, flags.min_free_bytes, flags.max_uploads,
                         [&](std::int64_t bytes) {
                           metrics.UploadBytes(bytes);
                           idle_trim.Received(bytes);
                         });
  StallWatch stalls(std::chrono::milliseconds(static_cast<std::int64_t>(flags.stall_timeout_s * 1000)));
  JobServiceImpl job_service(guard, coordinator, uploads, blobs, hub, workers, metrics, stalls);
  WorkerServiceImpl worker_service(
      guard, coordinator, uploads, blobs, workers, metrics, stalls,
      // A long poll is held at most half the alive window: a worker waiting in one for longer was
      // listed as gone and left out of endorecon_workers_connected (its --lease-wait 10 beside a
      // --lease-ttl-ms of 4000; found 2026-12-07).
      {std::chrono::milliseconds(flags.lease_ttl_ms), std::chrono::milliseconds(flags.heartbeat_ms),
       std::chrono::milliseconds(std::min<std::int64_t>(20000, flags.lease_ttl_ms / 2))});

  grpc::EnableDefaultHealthCheckService(true);
  grpc::ServerBuilder builder;
  int port = 0;
  builder.AddListeningPort(flags.listen, credentials, &port);
  builder.SetMaxReceiveMessageSize(kMaxMessageBytes);
  builder.SetMaxSendMessageSize(kMaxMessageBytes);
  // The sync server takes a thread per call in progress; the quota caps them, so peers that hold
  // calls open (a stalled download waits up to --stall-timeout) cannot take more threads, and the
  // memory of their chunks in flight, than this. Calls beyond it get RESOURCE_EXHAUSTED from gRPC.
  grpc::ResourceQuota quota("endorecon-server");
  quota.SetMaxThreads(flags.max_threads);
  builder.SetResourceQuota(quota);
  // No BDP probing: it widens every stream's receive window to megabytes, so each upload waiting
  // for its slot (UploadReceiver) would hold that much of its sender's bytes here. Without it a
  // stream that is read still gets a window as large as the message it waits for.
  builder.AddChannelArgument(GRPC_ARG_HTTP2_BDP_PROBE, 0);
  // gRPC sets SO_REUSEPORT on Linux: a second server started on the same port (a typo, a double
  // start) then listened beside this one and the kernel split new connections between them, jobs
  // included. Without it the second one fails with "the port is taken".
  builder.AddChannelArgument(GRPC_ARG_ALLOW_REUSEPORT, 0);
  builder.RegisterService(&job_service);
  builder.RegisterService(&worker_service);
  const auto server = builder.BuildAndStart();
  if (!server || port == 0) {
    Fail(ErrorCode::kUnavailable,
         "cannot listen on " + flags.listen +
             (flags.tls.tls()
                  ? ": the port is taken, or --tls-cert and --tls-key are no certificate and its key "
                    "(a key of another certificate; gRPC's log above says which)"
                  : ": the port is taken or the address is not this machine's"));
  }
  std::unique_ptr<HealthPort> health_port;
  if (!flags.health_listen.empty()) {
    health_port = std::make_unique<HealthPort>(flags.health_listen);
    spdlog::info("grpc.health.v1 only, in plaintext, on {}:{}", HostOf(flags.health_listen),
                 health_port->port());
  }

  const std::string address = HostOf(flags.listen) + ":" + std::to_string(port);
  spdlog::info("endorecon-server listening on {} ({}; data in {}, metrics {})", address,
               flags.tls.tls()
                   ? (flags.tls.client_ca_file.empty() ? "TLS" : "TLS, workers need a client certificate")
                   : "plaintext",
               data_dir.string(),
               flags.metrics_port >= 0 ? fmt::format("on {}:{}", flags.metrics_host, metrics.port()) : "off");
  // TLS beyond loopback without --tls-client-ca: a worker token alone admits a worker, and the
  // worker certificates of "Securing a deployment" step 1 are not asked for (only a log line's
  // "TLS" said so; found 2026-12-07).
  if (flags.tls.tls() && flags.tls.client_ca_file.empty() && !IsLoopbackAddress(flags.listen)) {
    spdlog::warn(
        "no --tls-client-ca: workers are not asked for a client certificate, so a worker token alone "
        "admits a worker (give --tls-client-ca CA.crt to require certificates signed by it)");
  }
  // /metrics has neither TLS nor tokens: beyond loopback, anyone who reaches it reads the queue's
  // and the workers' numbers (no patient data). Said, as --insecure is, not refused: a scraper on
  // another host is the usual deployment.
  if (flags.metrics_port >= 0 && !IsLoopbackAddress(MetricsAddress(flags.metrics_host, metrics.port()))) {
    spdlog::warn(
        "/metrics is served on {} in plaintext without tokens: keep that port behind a firewall or a "
        "network policy that lets only Prometheus reach it",
        flags.metrics_host);
  }
  // The newest job's submitter: a job submitted with a token, and no token store now, is a store
  // restored without its tokens (every caller saw every tenant's jobs, and only an info line said so;
  // found 2026-12-07).
  const auto newest = store.List({}, 1, 0).jobs;
  const bool tokens_before = !newest.empty() && !newest.front().submitted_by().empty();
  if (guard.Refresh()) {
    spdlog::info("tokens required: {}", TokenStore::PathIn(data_dir).string());
  } else if (tokens_before) {
    spdlog::warn(
        "no token store in {}, yet the newest job was submitted with a token ('{}'{}): was tokens.sqlite "
        "left out of a restore? Until it is back (docs/operations.md, \"Backup and restore\") every caller "
        "that reaches {} may use every API and see every tenant's jobs",
        data_dir.string(), newest.front().submitted_by(),
        newest.front().tenant().empty() ? "" : " of tenant '" + newest.front().tenant() + "'", address);
  } else if (flags.require_tokens) {
    spdlog::warn(
        "no token yet in {}: every call is refused (--require-tokens) until the first `endorecon-server "
        "token "
        "create --data-dir {} --role admin --name NAME` (picked up within a second)",
        data_dir.string(), data_dir.string());
  } else if (IsLoopbackAddress(flags.listen)) {
    spdlog::info(
        "no token store: every local caller may use every API (create tokens with `endorecon-server "
        "token create --data-dir {} --role admin --name NAME`; they are required from then on)",
        data_dir.string());
  } else {
    spdlog::warn(
        "no token store in {}: any caller that reaches {} may use every API until the first "
        "`endorecon-server token create --data-dir {} --role admin --name NAME` (picked up within a second)",
        data_dir.string(), address, data_dir.string());
  }
  if (flags.retention_days > 0) {
    spdlog::info("retention: files of jobs finished more than {} day(s) ago are deleted (checked every {} s)",
                 flags.retention_days, flags.retention_check_s);
  }
  if (flags.orphan_hours > 0) {
    spdlog::info(
        "files no job references are deleted once {} hour(s) have passed both since each was last written "
        "and since the server first found that no job names it (when "
        "each was first found is kept in {}, so a restart does not count the hours anew; a restored "
        "folder's files are first found at its first check; checked every {} s)",
        flags.orphan_hours, (data_dir / "orphans.json").string(), flags.retention_check_s);
  }

  std::atomic<bool> stopping{false};
  std::atomic<int> exit_code{0};
  std::thread maintenance([&] {
    auto next_retention = std::chrono::steady_clock::now();
    for (int tick = 0; !stopping; ++tick) {
      if (store.Broken()) {
        // What the coordinator holds may be ahead of the disk: restart and recover from the disk.
        spdlog::critical("stopping: the job store cannot commit (exit 75, for a supervisor to restart it)");
        exit_code = 75;
        ::kill(::getpid(), SIGTERM);
        return;
      }
      try {
        coordinator.ExpireLeases(Clock::now(), guard.OpenFailure());
      } catch (const Error& e) {
        spdlog::error("lease expiry: {}: {}", ErrorCodeName(e.code()), e.what());
      }
      if (tick % 5 == 0) {
        const bool writable = store.Writable();
        server->GetHealthCheckService()->SetServingStatus(writable);
        if (health_port) health_port->SetServing(writable);
        try {
          metrics.SetJobsByState(store.CountByState());
        } catch (const Error& e) {
          spdlog::error("job counts: {}: {}", ErrorCodeName(e.code()), e.what());
        }
        metrics.SetQueueDepth(scheduler.Depth());
        metrics.SetPendingUploads(coordinator.PendingUploadBytes());
        metrics.SetWorkersConnected(workers.CountAlive());
        std::error_code error;
        const auto space = std::filesystem::space(data_dir, error);
        if (!error)
          metrics.SetDataDisk(static_cast<std::int64_t>(space.available),
                              static_cast<std::int64_t>(space.capacity));
        metrics.SetDamagedFiles(blobs.DamagedCount());
        guard.Refresh();
        guard.FlushRefusals();
        grpc_log.FlushHeldBack();
        if (tick % 300 == 0) {
          try {
            guard.PublishTokenExpiries();
          } catch (const Error& e) {
            spdlog::error("token expiries: {}: {}", ErrorCodeName(e.code()), e.what());
          }
        }
        hub.Prune(std::chrono::steady_clock::now(), std::chrono::seconds(60));
        workers.Forget(std::chrono::steady_clock::now() - std::chrono::hours(24));  // `workers` lists a day
        const auto trim_start = IdleTrim::Clock::now();
        if (idle_trim.Tick(trim_start)) {
          spdlog::info(
              "uploads quiet: memory returned to the system in {} ms",
              std::chrono::duration_cast<std::chrono::milliseconds>(IdleTrim::Clock::now() - trim_start)
                  .count());
        }
      }
      if ((flags.retention_days > 0 || flags.orphan_hours > 0) &&
          std::chrono::steady_clock::now() >= next_retention) {
        next_retention +=
            std::chrono::milliseconds(static_cast<std::int64_t>(flags.retention_check_s * 1000));
        try {
          const auto plan = coordinator.ExpireFinishedBefore(JobCutoff(flags.retention_days),
                                                             OrphanCutoffFor(flags.orphan_hours));
          for (const auto& job : plan.jobs) guard.RecordServerAction("Retention", job.id(), "EXPIRED");
        } catch (const Error& e) {
          spdlog::error("retention: {}: {}", ErrorCodeName(e.code()), e.what());
        }
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(200));
    }
  });
  std::thread signal_waiter([&] {
    int signal = 0;
    sigwait(&stop_signals, &signal);
    // The job store's stop sends the server its own SIGTERM: that is not an operator's signal.
    if (exit_code == 0) spdlog::info("signal {}: shutting down", signal);
    stopping = true;
    scheduler.Shutdown();
    hub.Shutdown();
    server->Shutdown(std::chrono::system_clock::now() + std::chrono::seconds(2));
  });
  server->Wait();
  signal_waiter.join();
  maintenance.join();
  guard.FlushRefusals(/*all=*/true);  // no call is served now: the counts held back are whole
  spdlog::info("serving stopped; closing the job store, the DICOM threads and the data folder");
  return exit_code;
}

void AddSecurityFlags(CLI::App& app, ServerFlags& flags) {
  app.add_option("--tls-cert", flags.tls.cert_file, "serve gRPC over TLS with this certificate chain (PEM)");
  app.add_option("--tls-key", flags.tls.key_file,
                 "the certificate's private key (PEM; refused if others may read it)");
  app.add_option("--tls-client-ca", flags.tls.client_ca_file,
                 "the worker API requires a client certificate signed by this CA (mTLS)");
  app.add_flag("--insecure", flags.insecure, "allow a non-loopback --listen without TLS (logged loudly)");
  app.add_flag("--require-tokens", flags.require_tokens,
               "refuse every call while no token exists (without it, a server without tokens admits every "
               "caller); for a server started before its first token is made, as in Kubernetes");
  app.add_option(
         "--health-listen", flags.health_listen,
         "also answer grpc.health.v1 (only) in plaintext on this address, for probes that cannot use TLS")
      ->check(ListenAddress());
  app.add_option("--audit-log", flags.audit_log, "JSON Lines audit log (default: DATA_DIR/audit.jsonl)");
  app.add_option("--tenant-max-jobs", flags.tenant_quota.max_jobs,
                 "queued + running jobs each tenant may have (0: no limit)")
      ->capture_default_str()
      ->check(AtLeastZero());
  app.add_option("--tenant-max-bytes", flags.tenant_quota.max_bytes,
                 "bytes each tenant's jobs may keep stored, with its uploads not yet submitted (0: no limit)")
      ->capture_default_str()
      ->check(AtLeastZero());
  app.add_option("--quotas", flags.quotas_file, "JSON file of per-tenant quotas (overrides the two above)");
  app.add_option("--retention-days", flags.retention_days,
                 "delete clips and results of jobs finished longer ago than this (0: keep forever)")
      ->capture_default_str()
      ->check(AtLeastZero());
  app.add_option("--retention-check-s", flags.retention_check_s, "how often retention runs, in seconds")
      ->capture_default_str()
      ->check(AboveZero());
  app.add_option("--orphan-hours", flags.orphan_hours,
                 "delete stored files no job references (a running job's earlier checkpoints, uploads never "
                 "submitted, partial uploads) once this long has passed both since each was last written and "
                 "since the server first found that no job names it (kept in DATA_DIR/orphans.json; 0: keep "
                 "them)")
      ->capture_default_str()
      ->check(AtLeastZero());
}

void AddDicomFlags(CLI::App& app, ServerFlags& flags) {
  app.add_option("--ae-title", flags.dicom.ae_title,
                 "this server's DICOM AE title (calling, and its storage SCP's)")
      ->capture_default_str();
  app.add_option("--pacs", flags.pacs,
                 "a PACS, NAME=AET@HOST:PORT (repeatable): retrieve from it, send results to it");
  app.add_option(
         "--dicom-listen", flags.dicom.listen,
         "HOST:PORT of this server's storage SCP (where a PACS delivers C-MOVE retrievals); off by default")
      // std::stoi read "abc" as an exception, 99999 as a port and unix:PATH as its path's number
      // (found 2026-12-07).
      ->check(StorageScpAddress());
  app.add_option("--uid-root", flags.dicom.uid_root,
                 "UID root of the DICOM results' new UIDs (default: 2.25 UUID-derived UIDs)");
  app.add_option("--send-attempts", flags.dicom.send_attempts,
                 "attempts to send a job's DICOM results to one PACS before the send FAILS")
      ->capture_default_str()
      ->check(AboveZero());
  app.add_option("--send-backoff-ms", flags.dicom.send_backoff_ms,
                 "wait before the second send attempt, doubled for each further one (at most 60 s)")
      ->capture_default_str()
      ->check(AboveZero());
  app.add_option(
         "--retrieve-attempts", flags.dicom.retrieve_attempts,
         "attempts to retrieve a job's recording from a PACS that does not answer before the job FAILS")
      ->capture_default_str()
      ->check(AboveZero());
  app.add_option("--retrieve-backoff-ms", flags.dicom.retrieve_backoff_ms,
                 "wait before the second retrieval attempt, doubled for each further one (at most 60 s)")
      ->capture_default_str()
      ->check(AboveZero());
  app.add_option("--dicom-timeout", flags.dicom.timeout_s,
                 "seconds for a PACS to connect, associate and answer")
      ->capture_default_str()
      ->check(AboveZero());
}

}  // namespace

int main(int argc, char** argv) {
  ServerFlags flags;
  CLI::App app{"endorecon-server: queues reconstruction jobs durably and hands them to pulling workers"};
  app.set_version_flag("--version", ENDORECON_VERSION);  // server and workers run at one version
  app.add_option("--listen", flags.listen, "gRPC address host:port (loopback by default; port 0 picks one)")
      ->capture_default_str()
      ->check(ListenAddress());
  app.add_option("--data-dir", flags.data_dir, "where jobs (SQLite) and blobs are kept")
      ->capture_default_str();
  app.add_option("--metrics-port", flags.metrics_port, "Prometheus /metrics port (0 picks one, -1 disables)")
      ->capture_default_str()
      ->check(CLI::Range(-1, 65535));  // -2 turned metrics off, 70000 was 'the port is taken'
  app.add_option("--metrics-host", flags.metrics_host,
                 "interface for /metrics (plaintext; loopback by default)")
      ->capture_default_str();
  app.add_option("--max-upload-bytes", flags.max_upload_bytes, "largest upload accepted (sum of its files)")
      ->capture_default_str()
      ->check(AtLeastZero());
  app.add_option("--min-free-bytes", flags.min_free_bytes,
                 "free space uploads leave on the data disk, for the job store and accepted jobs' results")
      ->capture_default_str()
      ->check(AtLeastZero());
  app.add_option("--stall-timeout", flags.stall_timeout_s,
                 "seconds a download or watch stream may wait on a peer that takes no data before it is "
                 "cancelled")
      ->capture_default_str()
      ->check(AboveZero());
  app.add_option("--max-threads", flags.max_threads,
                 "calls the server serves at once (a thread each); more are refused with RESOURCE_EXHAUSTED")
      ->capture_default_str()
      ->check(CLI::Range(8, 100000));
  app.add_option("--max-uploads", flags.max_uploads,
                 "upload streams (clients' and workers') receiving at once; more wait their turn, their "
                 "bytes held in the sender")
      ->capture_default_str()
      ->check(CLI::Range(1, 10000));
  app.add_option("--max-attempts", flags.max_attempts,
                 "attempts before a job whose workers keep vanishing fails")
      ->capture_default_str()
      ->check(AboveZero());
  app.add_option("--lease-ttl-ms", flags.lease_ttl_ms,
                 "a running job whose worker is silent this long is requeued")
      ->capture_default_str()
      ->check(AboveZero());
  app.add_option("--heartbeat-ms", flags.heartbeat_ms,
                 "how often workers report (told to them at registration)")
      ->capture_default_str()
      ->check(AboveZero());
  AddSecurityFlags(app, flags);
  AddDicomFlags(app, flags);
  app.require_subcommand(0, 1);
  const auto token_command = AddTokenCommand(app);
  const auto retention_command = AddRetentionCommand(app);
  DecimalIntegers(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // A mistyped command or option is named, with the nearest known one (CLI11 said "A subcommand is
    // required" of a mistyped command).
    return endorecon::ExplainParseError(app, e, argc, argv);
  }
  if (app.got_subcommand("token") || app.got_subcommand("retention")) {
    // These print their result on stdout (a token, a plan): their log lines and errors go to stderr,
    // so a script reading stdout gets the result alone (an error's last word was taken for a token,
    // found 2026-12-06). The server's own log stays on stdout, for its supervisor.
    spdlog::set_default_logger(
        std::make_shared<spdlog::logger>("", std::make_shared<spdlog::sinks::stderr_color_sink_mt>()));
  }
  try {
    if (app.got_subcommand("token")) return token_command();
    if (app.got_subcommand("retention")) return retention_command();
    // Said once everything Run made is gone, the data folder's lock last: "stopped" came up to 3 s
    // before a new server could take the folder (found 2026-12-06).
    const int code = Run(flags);
    spdlog::info("endorecon-server stopped");
    return code;
  } catch (const endorecon::Error& e) {
    spdlog::error("{}: {}", endorecon::ErrorCodeName(e.code()), endorecon::PrintableLines(e.what()));
    // A file or folder the command line names and that is not there is its input's fault too.
    return e.code() == endorecon::ErrorCode::kInvalidArgument || e.code() == endorecon::ErrorCode::kNotFound
               ? 2
               : 1;
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return 1;
  }
}
