// Real processes over loopback for the service's integration tests: endorecon-server,
// endorecon-worker serve and the endorecon CLI, started from the build tree in a temp folder.
#pragma once

#include <sys/types.h>

#include <chrono>
#include <filesystem>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "endorecon/v1/job_service.grpc.pb.h"
#include "tests/unit/temp_dir.h"

namespace endorecon::testing {

// A child process whose stdout and stderr are appended to `log` (stderr to `err_log` when given).
// The destructor kills it (SIGKILL) if alive. One thread may Signal while another Waits: the pid is
// signalled only while the child is not reaped, so a recycled pid is never hit (bench/fault_campaign
// kills clients that other threads wait for).
class Process {
 public:
  Process(const std::vector<std::string>& argv, const std::filesystem::path& log,
          const std::filesystem::path& err_log = {});
  ~Process();
  Process(const Process&) = delete;
  Process& operator=(const Process&) = delete;
  // Sends `signal` unless the child was reaped; returns whether it was sent.
  bool Signal(int signal);
  // Waits for the exit; returns the exit code (128 + signal if killed).
  int Wait();
  std::string Log() const;
  pid_t pid() const { return pid_; }

 private:
  pid_t pid_ = -1;
  std::mutex mutex_;
  bool reaped_ = false;
  int status_ = 0;
  std::filesystem::path log_;
};

struct CliResult {
  int exit_code = -1;
  std::string out;  // stdout
  std::string err;  // stderr
};

// The path of a built binary: "server/endorecon-server", "client/endorecon", ...
std::string BuiltBinary(const std::string& relative);
// A TCP port free on 127.0.0.1 right now.
int FreePort();
// True when something accepts TCP connections on 127.0.0.1:`port`.
bool PortOpen(int port);
// Polls `condition` every 100 ms until it holds or `limit` (times kSlowdown in a sanitizer build)
// passes; returns whether it held.
bool WaitUntil(const std::function<bool()>& condition, std::chrono::seconds limit = std::chrono::seconds(60));
// Runs `endorecon --server ADDRESS args...` to completion.
CliResult RunCli(const std::string& address, const std::vector<std::string>& args);

// How a test's client reaches a server with TLS and tokens (empty: plaintext, no token).
struct ClientCredentials {
  std::string ca_file;
  std::string token_file;
  // The CLI's global options for these ("--ca", FILE, "--token-file", FILE).
  std::vector<std::string> CliFlags() const;
};
// Runs `endorecon-server token create --data-dir DIR ...` (`more`: further options, as --expires-in);
// returns the token (its output's last word).
std::string CreateToken(const std::filesystem::path& data_dir, const std::string& role,
                        const std::string& tenant, const std::string& name,
                        const std::vector<std::string>& more = {});
// Writes `token` into `path` with mode 0600; returns the path.
std::filesystem::path WriteTokenFile(const std::filesystem::path& path, const std::string& token);
// Runs `endorecon args...` to completion, with no --server added.
CliResult RunCliAsTyped(const std::vector<std::string>& args);
// Runs `argv` (a binary and its arguments) to completion, keeping its stdout and stderr.
CliResult RunCommand(const std::vector<std::string>& argv);
// Writes a tiny synthetic clip (endorecon-worker synth, 8 frames of 32x24) into `dir`.
void MakeClip(const std::filesystem::path& dir, int seed = 1);
// Makes the PNG at `path` hold `payload` too, in a private ancillary chunk (with its CRC, as the CLI
// checks) before its IEND, which decoders skip; returns the file's new bytes. A large file in a clip,
// for tests of large transfers (the CLI uploads only the files a clip's layout names).
std::string AddPngPayload(const std::filesystem::path& path, const std::string& payload);
// Runs a command line through the shell; returns its stdout (for curl).
std::string Capture(const std::string& command);

// A server (and workers) on loopback in a temp folder.
class Cluster {
 public:
  // Extra server flags are appended to the defaults (short leases and heartbeats). With `start`
  // false the test prepares the data folder (tokens) and credentials, then calls StartServer().
  explicit Cluster(std::vector<std::string> server_flags = {}, bool start = true);

  // The credentials of the cluster's own calls (its stub, Submit) from now on.
  void UseCredentials(const ClientCredentials& credentials);
  void StartServer();
  void KillServer(int signal);
  // The extra server flags of the next StartServer().
  void SetServerFlags(std::vector<std::string> flags) { server_flags_ = std::move(flags); }
  Process& StartWorker(const std::string& id, std::vector<std::string> flags = {});
  void StopWorker(const std::string& id, int signal);

  const std::string& address() const { return address_; }
  pid_t server_pid() const { return server_->pid(); }
  int metrics_port() const { return metrics_port_; }
  // The port the worker's /metrics took (it picks a free one, said in its "serving" line once it has
  // registered); 0 until then.
  int worker_metrics_port(const std::string& id) const;
  std::filesystem::path path(const std::string& name) const { return dir_ / name; }
  std::filesystem::path data_dir() const { return dir_ / "data"; }
  v1::JobService::Stub& stub() { return *stub_; }

  // The job, read through the API (throws on an RPC failure).
  v1::Job Job(const std::string& id);
  // Submits `clip` with the CLI; returns the job id.
  std::string Submit(const std::filesystem::path& clip, const std::vector<std::string>& flags);
  // Waits until the job reaches `state`; returns the job.
  v1::Job WaitForState(const std::string& id, v1::JobState state,
                       std::chrono::seconds limit = std::chrono::seconds(90));
  std::string ServerLog() const;

 private:
  TempDir dir_{"service"};
  std::vector<std::string> server_flags_;
  int port_ = 0;
  int metrics_port_ = 0;
  std::string address_;
  std::unique_ptr<Process> server_;
  int server_starts_ = 0;
  std::vector<std::pair<std::string, std::unique_ptr<Process>>> workers_;
  std::unique_ptr<v1::JobService::Stub> stub_;
  ClientCredentials credentials_;
};

// A new token in `cluster`'s store (running or not), written to <cluster folder>/<name>.token,
// with `ca_file` for TLS ("" for plaintext).
ClientCredentials MakeCredentials(const Cluster& cluster, const std::string& ca_file, const std::string& role,
                                  const std::string& tenant, const std::string& name);

}  // namespace endorecon::testing
