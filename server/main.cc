// endorecon-server: the job API (clients), the worker API (workers pull jobs), a durable job store,
// a content-addressed blob store, Prometheus metrics and grpc.health.v1. See docs/operations.md.
#include <grpcpp/grpcpp.h>
#include <grpcpp/health_check_service_interface.h>
#include <signal.h>
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <atomic>
#include <filesystem>
#include <thread>

#include "common/dicom/peer.h"
#include "common/dicom/storage_scp.h"
#include "common/dicom/uid.h"
#include "common/error.h"
#include "common/transport_security.h"
#include "server/dicom_retriever.h"
#include "server/dicom_sender.h"
#include "server/job_service.h"
#include "server/worker_service.h"

namespace {

using namespace endorecon;
using namespace endorecon::server;

struct ServerFlags {
  std::string listen = "127.0.0.1:50051";
  std::string data_dir = "endorecon-data";
  int metrics_port = 9464;
  std::int64_t max_upload_bytes = std::int64_t{20} << 30;
  int max_attempts = 3;
  std::int64_t lease_ttl_ms = 30000;
  std::int64_t heartbeat_ms = 2000;
  DicomSettings dicom;
  std::vector<std::string> pacs;
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
  const auto colon = flags.dicom.listen.rfind(':');
  if (colon == std::string::npos)
    FailInvalid("--dicom-listen '" + flags.dicom.listen + "': expected HOST:PORT");
  dicom::StorageScpSettings settings;
  settings.ae_title = flags.dicom.ae_title;
  settings.port = std::stoi(flags.dicom.listen.substr(colon + 1));
  settings.folder = folder;
  settings.calling_ae_titles = calling_ae_titles;
  auto scp = std::make_unique<dicom::StorageScp>(
      settings, [&retriever](const std::string& study, const std::filesystem::path&, std::int64_t bytes) {
        if (retriever != nullptr) retriever->Received(study, bytes);
      });
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

int Run(const ServerFlags& flags) {
  const sigset_t stop_signals = BlockStopSignals();
  const std::filesystem::path data_dir = flags.data_dir;
  std::filesystem::create_directories(data_dir);
  JobStore store(data_dir / "jobs.sqlite");
  BlobStore blobs(data_dir);
  Scheduler scheduler;
  LeaseTable leases(std::chrono::milliseconds(flags.lease_ttl_ms));
  WorkerRegistry workers(std::chrono::milliseconds(flags.lease_ttl_ms));
  WatchHub hub;
  Metrics metrics(flags.metrics_port >= 0 ? HostOf(flags.listen) + ":" + std::to_string(flags.metrics_port)
                                          : "");
  JobCoordinator coordinator({store, blobs, scheduler, leases, workers, hub, metrics}, flags.max_attempts);
  const PacsDirectory pacs(flags.pacs);
  DicomRetriever* retriever_for_scp = nullptr;
  std::vector<std::string> pacs_ae_titles;
  for (const auto& name : pacs.Names()) pacs_ae_titles.push_back(pacs.Find(name).ae_title);
  const auto scp = StartStorageScp(flags, data_dir / "dicom-incoming", pacs_ae_titles, retriever_for_scp);
  DicomRetriever retriever(coordinator, blobs, pacs, flags.dicom, metrics, data_dir / "retrievals",
                           scp.get());
  retriever_for_scp = &retriever;
  DicomSender sender(coordinator, blobs, pacs, flags.dicom, metrics);
  coordinator.SetDicomHooks({&pacs, flags.dicom.uid_root,
                             [&](const std::string& id) { retriever.Retrieve(id); },
                             [&](const std::string& id) { sender.Send(id); }});
  for (const auto& name : pacs.Names()) {
    spdlog::info("PACS {} = {} (this server calls as {})", name, dicom::PeerText(pacs.Find(name)),
                 flags.dicom.ae_title);
  }
  coordinator.Recover();
  UploadReceiver uploads(blobs, flags.max_upload_bytes,
                         [&](std::int64_t bytes) { metrics.UploadBytes(bytes); });
  JobServiceImpl job_service(coordinator, uploads, blobs, hub, workers, metrics);
  WorkerServiceImpl worker_service(
      coordinator, uploads, blobs, workers, metrics,
      {std::chrono::milliseconds(flags.lease_ttl_ms), std::chrono::milliseconds(flags.heartbeat_ms),
       std::chrono::milliseconds(20000)});

  grpc::EnableDefaultHealthCheckService(true);
  grpc::ServerBuilder builder;
  int port = 0;
  builder.AddListeningPort(flags.listen, ServerCredentials(), &port);
  builder.SetMaxReceiveMessageSize(kMaxMessageBytes);
  builder.SetMaxSendMessageSize(kMaxMessageBytes);
  builder.RegisterService(&job_service);
  builder.RegisterService(&worker_service);
  const auto server = builder.BuildAndStart();
  if (!server || port == 0) Fail(ErrorCode::kUnavailable, "cannot listen on " + flags.listen);
  auto* health = server->GetHealthCheckService();

  const std::string address = HostOf(flags.listen) + ":" + std::to_string(port);
  spdlog::info("endorecon-server listening on {} (data in {}, metrics on port {})", address,
               data_dir.string(), metrics.port());
  if (IsLoopbackAddress(flags.listen)) {
    spdlog::info("listening on loopback only; pass --listen 0.0.0.0:{} to serve other machines", port);
  } else {
    spdlog::warn(
        "listening beyond loopback on {} without TLS or tokens (not implemented yet): anyone who can reach "
        "this port can submit jobs and read results; keep it on a trusted network",
        flags.listen);
  }

  std::atomic<bool> stopping{false};
  std::thread maintenance([&] {
    int tick = 0;
    while (!stopping) {
      coordinator.ExpireLeases(Clock::now());
      if (tick++ % 5 == 0) {
        const bool writable = store.Writable();
        health->SetServingStatus(writable);
        metrics.SetJobsByState(store.CountByState());
        metrics.SetQueueDepth(scheduler.Depth());
        metrics.SetWorkersConnected(workers.CountAlive());
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(200));
    }
  });
  std::thread signal_waiter([&] {
    int signal = 0;
    sigwait(&stop_signals, &signal);
    spdlog::info("signal {}: shutting down", signal);
    stopping = true;
    scheduler.Shutdown();
    hub.Shutdown();
    server->Shutdown(std::chrono::system_clock::now() + std::chrono::seconds(2));
  });
  server->Wait();
  signal_waiter.join();
  maintenance.join();
  spdlog::info("endorecon-server stopped");
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  ServerFlags flags;
  CLI::App app{"endorecon-server: queues reconstruction jobs durably and hands them to pulling workers"};
  app.add_option("--listen", flags.listen, "gRPC address host:port (loopback by default; port 0 picks one)")
      ->capture_default_str();
  app.add_option("--data-dir", flags.data_dir, "where jobs (SQLite) and blobs are kept")
      ->capture_default_str();
  app.add_option("--metrics-port", flags.metrics_port,
                 "Prometheus /metrics port on the --listen host (0 picks one, -1 disables)")
      ->capture_default_str();
  app.add_option("--max-upload-bytes", flags.max_upload_bytes, "largest upload accepted (sum of its files)")
      ->capture_default_str();
  app.add_option("--max-attempts", flags.max_attempts,
                 "attempts before a job whose workers keep vanishing fails")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  app.add_option("--lease-ttl-ms", flags.lease_ttl_ms,
                 "a running job whose worker is silent this long is requeued")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  app.add_option("--heartbeat-ms", flags.heartbeat_ms,
                 "how often workers report (told to them at registration)")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  app.add_option("--ae-title", flags.dicom.ae_title,
                 "this server's DICOM AE title (calling, and its storage SCP's)")
      ->capture_default_str();
  app.add_option("--pacs", flags.pacs,
                 "a PACS, NAME=AET@HOST:PORT (repeatable): retrieve from it, send results to it");
  app.add_option(
      "--dicom-listen", flags.dicom.listen,
      "HOST:PORT of this server's storage SCP (where a PACS delivers C-MOVE retrievals); off by default");
  app.add_option("--uid-root", flags.dicom.uid_root,
                 "UID root of the DICOM results' new UIDs (default: 2.25 UUID-derived UIDs)");
  app.add_option("--send-attempts", flags.dicom.send_attempts,
                 "attempts to send a job's DICOM results to one PACS before the send FAILS")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  app.add_option("--send-backoff-ms", flags.dicom.send_backoff_ms,
                 "wait before the second send attempt, doubled for each further one (at most 60 s)")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  app.add_option("--dicom-timeout", flags.dicom.timeout_s,
                 "seconds for a PACS to connect, associate and answer")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  CLI11_PARSE(app, argc, argv);
  try {
    dicom::CheckAeTitle(flags.dicom.ae_title, "--ae-title");
    if (!flags.dicom.uid_root.empty()) dicom::NewUid(flags.dicom.uid_root);  // refuses a malformed root now
    return Run(flags);
  } catch (const endorecon::Error& e) {
    spdlog::error("{}: {}", endorecon::ErrorCodeName(e.code()), e.what());
    return 1;
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return 1;
  }
}
