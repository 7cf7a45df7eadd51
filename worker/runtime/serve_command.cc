// endorecon-worker serve: registers with endorecon-server, then runs one lease loop per device.
// SIGTERM/SIGINT: running jobs stop at their next iteration, their last checkpoint is reported and
// they are handed back to the queue (not counted as a lost attempt); then the process exits.
#include <signal.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdlib>
#include <memory>
#include <optional>
#include <string_view>
#include <thread>

#include "common/cli_checks.h"
#include "common/error.h"
#include "common/folder_lock.h"
#include "common/grpc_log.h"
#include "common/job_bounds.h"
#include "common/metrics_exposer.h"
#include "common/private_folder.h"
#include "common/transport_security.h"
#include "common/warning_pacer.h"
#include "worker/runtime/commands.h"
#include "worker/runtime/device_list.h"
#include "worker/runtime/idle_watch.h"
#include "worker/runtime/job_runner.h"
#include "worker/runtime/prometheus_target_file.h"
#include "worker/runtime/worker_client.h"
#include "worker/runtime/worker_metrics.h"

namespace endorecon::worker {
namespace {

struct ServeFlags {
  std::string server = "127.0.0.1:50051";
  std::string devices = "cpu";
  std::string metrics_host = "127.0.0.1";
  int metrics_port = 9465;
  std::string work_dir;
  std::int64_t min_free_bytes = std::int64_t{256} << 20;
  std::string id;
  int threads = 0;
  double timeout_s = 30;
  double lease_wait_s = 10;
  double preview_interval_s = 30;
  double checkpoint_interval_s = 120;
  std::string ca_file;
  std::string tls_cert;
  std::string tls_key;
  std::string token_file;
  bool insecure = false;
  double exit_when_idle_s = 0;
  std::string prometheus_target_file;
};

ChannelSecurity SecurityOf(const ServeFlags& flags) {
  ChannelSecurity security;
  security.ca_file = flags.ca_file;
  security.cert_file = flags.tls_cert;
  security.key_file = flags.tls_key;
  security.token_file = flags.token_file;  // read again when rotated (transport_security.h)
  security.insecure = flags.insecure;
  return security;
}

// A refusal that retrying cannot change: the worker's credentials are wrong.
bool Refused(const Error& error) {
  return error.code() == ErrorCode::kUnauthenticated || error.code() == ErrorCode::kPermissionDenied;
}

std::string Hostname() {
  char name[256] = {};
  gethostname(name, sizeof(name) - 1);
  return name;
}

// The time `file` was last written, or none (no file, or it cannot be read).
std::optional<std::filesystem::file_time_type> WrittenAt(const std::string& file) {
  std::error_code error;
  const auto at = std::filesystem::last_write_time(file, error);
  if (file.empty() || error) return std::nullopt;
  return at;
}

// Whether the worker has been idle for --exit-when-idle; the first loop to see it stops them all.
bool LeaveIdle(IdleWatch& idle, WorkerClient& client, std::atomic<bool>& shutting_down) {
  const double idle_s = static_cast<double>(idle.limit().count()) / 1000;
  if (!idle.Due(std::chrono::steady_clock::now())) return false;
  if (!shutting_down.exchange(true)) {  // not stopping for a signal already
    idle.Leave();
    if (idle.ScratchWasFull()) {
      spdlog::error(
          "no job for {} s: the scratch folder has had no room to take one (--min-free-bytes), so the "
          "queue was not asked (--exit-when-idle): stopping (exit {})",
          idle_s, kIdleScratchFullExit);
    } else if (idle.ServerFailing()) {
      spdlog::error(
          "no job for {} s and the server cannot be reached or refuses this worker (--exit-when-idle): "
          "stopping (exit {})",
          idle_s, kIdleUnreachableExit);
    } else {
      spdlog::info("no job for {} s (--exit-when-idle): stopping", idle_s);
    }
    client.CancelLeases();  // the other devices' long polls
  }
  return true;
}

// Ends the device's job for the idle watch however the job ends.
struct JobOnDevice {
  explicit JobOnDevice(IdleWatch& idle) : idle(idle) { idle.JobStarted(); }
  ~JobOnDevice() { idle.JobEnded(std::chrono::steady_clock::now()); }
  JobOnDevice(const JobOnDevice&) = delete;
  JobOnDevice& operator=(const JobOnDevice&) = delete;
  IdleWatch& idle;
};

void LeaseLoop(WorkerClient& client, const Device& device, const RunnerSettings& settings,
               WorkerMetrics& metrics, std::atomic<bool>& shutting_down, std::chrono::milliseconds wait,
               const std::string& token_file, IdleWatch& idle) {
  using Clock = std::chrono::steady_clock;
  auto backoff = std::chrono::milliseconds(500);
  std::optional<Clock::time_point> failing_since;  // since when calls fail, while they do
  WarningPacer warnings;
  std::string last_error;
  bool waiting_for_space = false;
  auto disk_backoff = std::chrono::seconds(30);
  while (!shutting_down) {
    if (LeaveIdle(idle, client, shutting_down)) break;
    // A full scratch folder takes no job: it would only fail there.
    const std::int64_t free_bytes = ScratchFree(settings.work_dir);
    if (free_bytes >= 0 && free_bytes < settings.min_free_bytes) {
      if (!waiting_for_space) {
        spdlog::warn("[{}] scratch folder {} has {} bytes free (--min-free-bytes {}): leasing no job until "
                     "there is room",
                     device.name, settings.work_dir.string(), free_bytes, settings.min_free_bytes);
      }
      waiting_for_space = true;
      idle.ScratchFull(true);
      std::this_thread::sleep_for(std::chrono::seconds(1));
      continue;
    }
    if (waiting_for_space) spdlog::info("[{}] scratch folder has room again", device.name);
    waiting_for_space = false;
    idle.ScratchFull(false);
    try {
      // A poll of at least 200 ms: one of none would spin while another device's job ends.
      const auto lease = client.Lease(device.name, std::max(idle.Left(std::chrono::steady_clock::now(), wait),
                                                            std::chrono::milliseconds(200)));
      idle.ServerAnswered(true);
      if (failing_since) {
        spdlog::info("[{}] the server answers again ({} s after the first failure)", device.name,
                     std::chrono::duration_cast<std::chrono::seconds>(Clock::now() - *failing_since).count());
      }
      failing_since.reset();
      warnings.Reset();
      backoff = std::chrono::milliseconds(500);
      const auto run_until_scratch_full = [&] {
        const JobOnDevice job(idle);
        return RunLeasedJob(client, *lease, device, settings, metrics, shutting_down);
      };
      if (lease && run_until_scratch_full()) {
        // The job needed more scratch than this worker has: leave it to others for a while
        // (30 s, doubling to 10 minutes while it keeps happening).
        spdlog::warn("[{}] scratch folder full: taking no job for {} s", device.name, disk_backoff.count());
        for (auto waited = std::chrono::seconds(0); waited < disk_backoff && !shutting_down;
             waited += std::chrono::seconds(1)) {
          std::this_thread::sleep_for(std::chrono::seconds(1));
        }
        disk_backoff = std::min(disk_backoff * 2, std::chrono::seconds(600));
      } else if (lease) {
        disk_backoff = std::chrono::seconds(30);
      }
    } catch (const Error& e) {
      idle.ServerAnswered(false);
      // Retried at most 2 s apart (the channel's own reconnect backoff), so a restarted server has
      // its workers back within a second; while it stays away, a warning every 30 s, not every retry.
      // Another error than the last is said at once.
      if (e.what() != last_error) warnings.Reset();
      last_error = e.what();
      if (int held = 0; warnings.Due(held)) {
        spdlog::warn("[{}] {}: {}; retrying every {}{}", device.name, ErrorCodeName(e.code()), e.what(),
                     Refused(e) ? "30 s at most (write a valid worker token into --token-file)" : "2 s",
                     failing_since ? " (still failing; warned every 30 s)" : "");
      }
      if (!failing_since) failing_since = Clock::now();
      // A refused token (revoked, expired, or tokens switched on after this worker started) is not
      // back in 2 s: retried up to 30 s apart, each retry an audit line (one every 2 s was 1,800 an
      // hour; found 2026-12-05). A rotated --token-file is taken at the next retry.
      const bool refused = Refused(e);
      const auto most = refused ? std::chrono::milliseconds(30000) : std::chrono::milliseconds(2000);
      const auto token_written = WrittenAt(token_file);
      bool rotated = false;
      for (auto paused = std::chrono::milliseconds(0); paused < backoff && !shutting_down && !rotated;
           paused += std::chrono::milliseconds(1000)) {
        client.PauseBeforeRetry(std::min(backoff - paused, std::chrono::milliseconds(1000)));
        rotated = refused && WrittenAt(token_file) != token_written;
      }
      backoff = rotated ? std::chrono::milliseconds(500) : std::min(backoff * 2, most);
    }
  }
}

int Serve(const ServeFlags& flags) {
  sigset_t stop_signals;
  sigemptyset(&stop_signals);
  sigaddset(&stop_signals, SIGINT);
  sigaddset(&stop_signals, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &stop_signals, nullptr);

  auto devices =
      ParseDevices(flags.devices, flags.threads, static_cast<int>(std::thread::hardware_concurrency()));
  DescribeDevices(devices);
  const std::string worker_id = flags.id.empty() ? Hostname() + "-" + std::to_string(getpid()) : flags.id;
  try {  // the server's rule, before anything starts
    ValidateWorkerId(worker_id);
  } catch (const Error& e) {
    FailInvalid("--id: " + std::string(e.what()));
  }
  // gRPC's own lines (two a second while --ca does not verify the server) into the log, paced; the
  // worker's own warning says which side to look at.
  const GrpcLogRoute grpc_log(
      "the server's certificate does not verify against --ca, or the server does not trust this "
      "worker's --tls-cert: the warning beside says which",
      {});
  // The credentials (read and checked here) before the metrics port: a certificate refused at start
  // was hidden behind "cannot serve metrics" when the port was taken (CI, 2026-12-07).
  WorkerClient client(flags.server, SecurityOf(flags), worker_id,
                      std::chrono::milliseconds(static_cast<long>(flags.timeout_s * 1000)));
  WorkerMetrics metrics(flags.metrics_port >= 0 ? MetricsAddress(flags.metrics_host, flags.metrics_port) : "",
                        devices);
  std::vector<std::string> names;
  for (const auto& device : devices) names.push_back(device.name);

  RunnerSettings settings;
  settings.work_dir = flags.work_dir.empty()
                          ? DefaultWorkDir(std::filesystem::temp_directory_path(), worker_id)
                          : std::filesystem::path(flags.work_dir);
  settings.min_free_bytes = flags.min_free_bytes;
  // The default scratch folder is this process's alone: gone with it at every stop (its job folders
  // went with their jobs; a folder given by --work-dir stays for the next worker).
  const auto remove_default_scratch = [&] {
    std::error_code ignored;
    if (flags.work_dir.empty()) std::filesystem::remove_all(settings.work_dir, ignored);
  };
  settings.preview_interval_s = flags.preview_interval_s;
  settings.checkpoint_interval_s = flags.checkpoint_interval_s;
  if (MakePrivateFolder(settings.work_dir)) {
    spdlog::warn(
        "{} is open to its group or others, and holds patient data while jobs run: make it its "
        "owner's alone (chmod 700)",
        settings.work_dir.string());
  }
  // One worker per scratch folder: a second one's start cleared the first's running jobs.
  const FolderLock scratch_lock(settings.work_dir, kWorkerLockFile, "endorecon-worker", "scratch folder");
  if (const int removed = RemoveLeftoverJobs(settings.work_dir))
    spdlog::info("removed {} job folder(s) an earlier run left in {}", removed, settings.work_dir.string());
  if (flags.work_dir.empty()) {
    const auto temp = std::filesystem::temp_directory_path();
    if (const int removed = RemoveDeadWorkersFolders(temp, Hostname()))
      spdlog::info("removed {} scratch folder(s) of workers on this host that are gone, in {}", removed,
                   temp.string());
  }
  std::atomic<bool> shutting_down{false};
  std::atomic<bool> stopped{false};  // serving ended: the waiter is woken to return, not by a signal
  // A second signal stops at once: a job hands itself back at the end of its training step, and an
  // operator who cannot wait for that (a step of a large configuration took minutes; found
  // 2026-12-06) need not reach for kill -9. The job's lease then expires and it runs again elsewhere.
  std::thread signal_waiter([&] {
    int signal = 0;
    sigwait(&stop_signals, &signal);
    if (shutting_down.exchange(true) || stopped) return;  // the refused registration below, or the end
    spdlog::info("signal {}: handing running jobs back and stopping (a second signal stops at once)", signal);
    client.CancelLeases();
    // A signal within a second of the first is its echo: GNU timeout and a kill of the process group
    // deliver one signal twice, which stopped the worker at once, its jobs' hand-back lost (found
    // 2026-12-07). An operator's second signal comes later.
    const auto first = std::chrono::steady_clock::now();
    for (;;) {
      sigwait(&stop_signals, &signal);
      if (stopped) return;
      if (std::chrono::steady_clock::now() - first >= std::chrono::seconds(1)) break;
      spdlog::info(
          "signal {} again within a second: taken as the first's echo (send it again to stop at once)",
          signal);
    }
    spdlog::warn("signal {} again: stopping now; the running jobs' leases expire and they run again", signal);
    std::_Exit(128 + signal);
  });
  const auto stop_waiter = [&] {
    stopped = true;
    pthread_kill(signal_waiter.native_handle(), SIGTERM);
    signal_waiter.join();
  };
  // Retried every second (a server not up yet: as soon as it is); said at the first failure and then
  // every 30 s, not every retry (a refused certificate wrote a line a second for as long as it ran).
  const auto register_start = std::chrono::steady_clock::now();
  IdleWatch idle(std::chrono::milliseconds(static_cast<std::int64_t>(flags.exit_when_idle_s * 1000)),
                 register_start);
  WarningPacer pacer;
  int attempts = 0;
  while (!shutting_down) {
    try {
      ++attempts;
      const auto registered = client.Register(Hostname(), devices);
      settings.heartbeat = std::chrono::milliseconds(registered.heartbeat_interval_ms());
      if (registered.lease_ttl_ms() > 0)
        settings.lease_ttl = std::chrono::milliseconds(registered.lease_ttl_ms());
      break;
    } catch (const Error& e) {
      if (Refused(e)) {
        shutting_down = true;
        stop_waiter();
        remove_default_scratch();  // it stayed until a later start cleared it (found 2026-12-07)
        throw;
      }
      if (idle.Due(std::chrono::steady_clock::now())) {  // stopped below, as for a signal
        idle.ServerAnswered(false);
        idle.Leave();
        shutting_down = true;
        spdlog::error("cannot register with {} after {} s (--exit-when-idle): {}; stopping (exit {})",
                      flags.server, flags.exit_when_idle_s, e.what(), kIdleUnreachableExit);
        break;
      }
      // A server that refuses this worker's client certificate closes the connection in the TLS
      // handshake; gRPC says only "Socket closed", so the likely reasons are named (TLS over plain
      // TCP says "wrong version number" or the like, a refused server certificate "certificate").
      const std::string_view message = e.what();
      const bool closed = message.find("Socket closed") != std::string_view::npos ||
                          message.find("handshake") != std::string_view::npos;
      ChannelSecurity security;
      security.ca_file = flags.ca_file;
      const std::string tls_hint = TlsFailureHint(message, security);
      const bool handshake = !flags.ca_file.empty() && closed && tls_hint.empty();
      // Plaintext to a TLS port: the server drops the connection too (the CLI hints at --ca alike).
      const bool plaintext_to_tls = flags.ca_file.empty() && closed;
      if (int held = 0; !pacer.Due(held)) {
        client.PauseBeforeRetry(std::chrono::seconds(1));
        continue;
      }
      const auto waited =
          std::chrono::duration_cast<std::chrono::seconds>(std::chrono::steady_clock::now() - register_start)
              .count();
      spdlog::warn(
          "cannot register with {}{}: {}; retrying every second{}", flags.server,
          attempts > 1 ? fmt::format(" ({} attempts in {} s)", attempts, waited) : "", e.what(),
          !tls_hint.empty() ? " (" + tls_hint + ")"
          : handshake && !flags.tls_cert.empty()
              ? " (the server closed the connection in the TLS handshake: is --tls-cert signed by the "
                "server's --tls-client-ca?)"
          : handshake        ? " (the server closed the connection in the TLS handshake: does it require a "
                               "client certificate, --tls-cert and --tls-key?)"
          : plaintext_to_tls ? " (the server closed the connection: if it serves TLS, give --ca FILE)"
                             : "");
      client.PauseBeforeRetry(std::chrono::seconds(1));
    }
  }
  if (shutting_down) {  // a signal (or --exit-when-idle) before the server took the worker: it never served
    stop_waiter();
    remove_default_scratch();
    spdlog::info("worker {} stopped before it could register with {}", worker_id, flags.server);
    return idle.ExitCode();
  }
  spdlog::info("worker {} serving {} with {} device(s) [{}], metrics {}", worker_id, flags.server,
               devices.size(), fmt::join(names, ","),
               flags.metrics_port >= 0 ? fmt::format("on port {} of {}", metrics.port(), flags.metrics_host)
                                       : std::string("off"));
  const bool metrics_on_loopback =
      IsLoopbackAddress(MetricsAddress(flags.metrics_host, std::max(metrics.port(), 0)));
  // As the server's: /metrics has neither TLS nor tokens (it carries no patient data).
  if (flags.metrics_port >= 0 && !metrics_on_loopback) {
    spdlog::warn(
        "/metrics is served on {} in plaintext without tokens: keep that port behind a firewall or a "
        "network policy that lets only Prometheus reach it",
        flags.metrics_host);
  }
  std::optional<PrometheusTargetFile> target_file;
  if (!flags.prometheus_target_file.empty() && flags.metrics_port < 0) {
    spdlog::warn("--prometheus-target-file {}: none written, as metrics are off (--metrics-port -1)",
                 flags.prometheus_target_file);
  }
  if (!flags.prometheus_target_file.empty() && flags.metrics_port >= 0) {
    const auto host = ScrapeHost(flags.metrics_host, Hostname());
    target_file.emplace(flags.prometheus_target_file, host, metrics.port(), worker_id);
    // A loopback target is a warning: the file is for a Prometheus that finds workers it does not run
    // beside (a warning filter missed it as an info line; found 2026-12-07).
    spdlog::log(metrics_on_loopback ? spdlog::level::warn : spdlog::level::info,
                "Prometheus target {}:{} written to {}{}", host, metrics.port(), flags.prometheus_target_file,
                metrics_on_loopback
                    ? " (only this machine reaches it: a Prometheus elsewhere needs --metrics-host set to "
                      "this machine's address on its network, or 0.0.0.0)"
                    : "");
  }
  std::vector<std::thread> loops;
  const auto wait = std::chrono::milliseconds(static_cast<long>(flags.lease_wait_s * 1000));
  for (const auto& device : devices) {
    loops.emplace_back([&, device] {
      LeaseLoop(client, device, settings, metrics, shutting_down, wait, flags.token_file, idle);
    });
  }
  for (auto& loop : loops) loop.join();
  stop_waiter();
  client.Leave();  // its jobs are handed back by now
  remove_default_scratch();
  spdlog::info("worker {} stopped", worker_id);
  return idle.ExitCode();
}

}  // namespace

Command AddServeCommand(CLI::App& app) {
  auto flags = std::make_shared<ServeFlags>();
  auto* cmd =
      app.add_subcommand("serve", "lease jobs from endorecon-server and run them, one engine per device");
  cmd->add_option("--server", flags->server, "server address host:port")
      ->capture_default_str()
      ->check(ServerAddress());
  cmd->add_option("--devices", flags->devices,
                  "cpu, cpu:N (N slots) or CUDA device indices 0,1,... (one engine each)")
      ->capture_default_str();
  cmd->add_option("--metrics-port", flags->metrics_port,
                  "Prometheus /metrics port (0 picks one, -1 disables)")
      ->capture_default_str()
      ->check(CLI::Range(-1, 65535));
  cmd->add_option("--metrics-host", flags->metrics_host, "interface for /metrics")->capture_default_str();
  cmd->add_option("--work-dir", flags->work_dir, "scratch folder for running jobs (default: in $TMPDIR)");
  cmd->add_option("--min-free-bytes", flags->min_free_bytes,
                  "free space the scratch folder needs to take a job; a job failing below it is handed back "
                  "uncounted")
      ->capture_default_str()
      ->check(AtLeastZero());
  cmd->add_option("--id", flags->id, "worker id (default: hostname-pid)");
  // Each bounded: --lease-wait -1 busy-polled an idle queue, --threads -3 was taken (found 2026-12-05).
  cmd->add_option("--threads", flags->threads, "engine threads per device (0: cores / devices)")
      ->capture_default_str()
      ->check(AtLeastZero());
  cmd->add_option("--timeout", flags->timeout_s, "deadline of each call in seconds")
      ->capture_default_str()
      ->check(AboveZero());
  cmd->add_option("--lease-wait", flags->lease_wait_s, "long-poll for a job this many seconds")
      ->capture_default_str()
      ->check(AboveZero());
  cmd->add_option("--preview-interval", flags->preview_interval_s, "seconds between previews")
      ->capture_default_str()
      ->check(AboveZero());
  cmd->add_option("--checkpoint-interval", flags->checkpoint_interval_s, "seconds between checkpoints")
      ->capture_default_str()
      ->check(AboveZero());
  cmd->add_option("--ca", flags->ca_file, "TLS: verify the server against this CA certificate");
  cmd->add_option("--tls-cert", flags->tls_cert, "client certificate for a server that requires one (mTLS)");
  cmd->add_option("--tls-key", flags->tls_key, "its private key (refused if others may read it)");
  cmd->add_option("--token-file", flags->token_file, "file holding the worker's bearer token (mode 0600)");
  cmd->add_option(
         "--exit-when-idle", flags->exit_when_idle_s,
         "stop after this many seconds without a job on any device (0: never; for batch allocations); "
         "exit 69 when the server could not be reached or refused this worker meanwhile")
      ->capture_default_str()
      ->check(AtLeastZero());
  cmd->add_option(
      "--prometheus-target-file", flags->prometheus_target_file,
      "write a Prometheus file_sd target naming this worker's /metrics here while it serves (batch "
      "allocations: a Prometheus reading the folder finds each worker wherever it runs)");
  cmd->add_flag("--insecure", flags->insecure,
                "send the token without TLS to a server beyond loopback (isolated test networks only)");
  return [flags] { return Serve(*flags); };
}

}  // namespace endorecon::worker
