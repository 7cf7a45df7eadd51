#include "tests/integration/service_harness.h"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>
#include <zlib.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string_view>
#include <thread>

#include "common/grpc_status.h"
#include "common/transport_security.h"
#include "tests/integration/sanitizer_build.h"

namespace endorecon::testing {
namespace fs = std::filesystem;
namespace {

ChannelSecurity ChannelSecurityOf(const ClientCredentials& credentials) {
  ChannelSecurity security;
  security.ca_file = credentials.ca_file;
  if (!credentials.token_file.empty()) security.token = ReadTokenFile(credentials.token_file, "token file");
  return security;
}

}  // namespace

Process::Process(const std::vector<std::string>& argv, const fs::path& log, const fs::path& err_log)
    : log_(log) {
  // Everything the child needs is made before fork: the tests fork from many threads at once, and a
  // child of a threaded process may call only async-signal-safe functions before execv. A malloc
  // there (this argument list was once built in the child) can wait forever on a lock another thread
  // held at the fork: ManyClientsTest hung 30 minutes under ASan so (2026-12-01).
  std::vector<char*> args;
  for (const auto& arg : argv) args.push_back(const_cast<char*>(arg.c_str()));
  args.push_back(nullptr);
  const std::string out_path = log.string(), err_path = err_log.string();
  pid_ = fork();
  if (pid_ < 0) throw std::runtime_error("fork failed");
  if (pid_ == 0) {
    const int fd = ::open(out_path.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
    const int err = err_path.empty() ? fd : ::open(err_path.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
    dup2(fd, STDOUT_FILENO);
    dup2(err, STDERR_FILENO);
    execv(args[0], args.data());
    _exit(127);
  }
}

Process::~Process() {
  Signal(SIGKILL);
  Wait();
}

bool Process::Signal(int signal) {
  std::lock_guard lock(mutex_);
  return !reaped_ && kill(pid_, signal) == 0;
}

int Process::Wait() {
  // Waits without reaping, then reaps under the lock Signal takes.
  siginfo_t info{};
  while (waitid(P_PID, static_cast<id_t>(pid_), &info, WEXITED | WNOWAIT) != 0 && errno == EINTR) {
  }
  std::lock_guard lock(mutex_);
  if (!reaped_) {
    waitpid(pid_, &status_, 0);
    reaped_ = true;
  }
  return WIFEXITED(status_) ? WEXITSTATUS(status_) : 128 + WTERMSIG(status_);
}

std::string Process::Log() const { return ReadBytes(log_); }

std::string BuiltBinary(const std::string& relative) {
  return std::string(ENDORECON_BINARY_DIR) + "/" + relative;
}

int FreePort() {
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  address.sin_port = 0;
  bind(fd, reinterpret_cast<sockaddr*>(&address), sizeof(address));
  socklen_t length = sizeof(address);
  getsockname(fd, reinterpret_cast<sockaddr*>(&address), &length);
  close(fd);
  return ntohs(address.sin_port);
}

bool PortOpen(int port) {
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  address.sin_port = htons(static_cast<std::uint16_t>(port));
  const bool open = connect(fd, reinterpret_cast<sockaddr*>(&address), sizeof(address)) == 0;
  close(fd);
  return open;
}

bool WaitUntil(const std::function<bool()>& condition, std::chrono::seconds limit) {
  const auto give_up = std::chrono::steady_clock::now() + limit * kSlowdown;
  while (std::chrono::steady_clock::now() < give_up) {
    if (condition()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  return condition();
}

CliResult RunCli(const std::string& address, const std::vector<std::string>& args) {
  std::vector<std::string> with_server{"--server", address};
  with_server.insert(with_server.end(), args.begin(), args.end());
  return RunCliAsTyped(with_server);
}

CliResult RunCliAsTyped(const std::vector<std::string>& args) {
  std::vector<std::string> argv{BuiltBinary("client/endorecon")};
  argv.insert(argv.end(), args.begin(), args.end());
  return RunCommand(argv);
}

CliResult RunCommand(const std::vector<std::string>& argv) {
  TempDir scratch("cli");
  CliResult result;
  result.exit_code = Process(argv, scratch / "out", scratch / "err").Wait();
  result.out = ReadBytes(scratch / "out");
  result.err = ReadBytes(scratch / "err");
  return result;
}

std::vector<std::string> ClientCredentials::CliFlags() const {
  std::vector<std::string> flags;
  if (!ca_file.empty()) flags.insert(flags.end(), {"--ca", ca_file});
  if (!token_file.empty()) flags.insert(flags.end(), {"--token-file", token_file});
  return flags;
}

std::string CreateToken(const fs::path& data_dir, const std::string& role, const std::string& tenant,
                        const std::string& name, const std::vector<std::string>& more) {
  TempDir scratch("token");
  std::vector<std::string> argv{BuiltBinary("server/endorecon-server"),
                                "token",
                                "create",
                                "--data-dir",
                                data_dir.string(),
                                "--role",
                                role,
                                "--name",
                                name};
  if (!tenant.empty()) argv.insert(argv.end(), {"--tenant", tenant});
  argv.insert(argv.end(), more.begin(), more.end());
  if (Process(argv, scratch / "out").Wait() != 0)
    throw std::runtime_error("token create failed: " + ReadBytes(scratch / "out"));
  const std::string out = ReadBytes(scratch / "out");
  const auto end = out.find_last_not_of(" \n");
  const auto begin = out.find_last_of(" \n", end);
  return out.substr(begin + 1, end - begin);
}

fs::path WriteTokenFile(const fs::path& path, const std::string& token) {
  WriteBytes(path, token + "\n");
  fs::permissions(path, fs::perms::owner_read | fs::perms::owner_write);
  return path;
}

void MakeClip(const fs::path& dir, int seed) {
  const std::string command = BuiltBinary("worker/runtime/endorecon-worker") + " synth " + dir.string() +
                              " --frames 8 --width 32 --height 24 --seed " + std::to_string(seed) +
                              " > /dev/null 2>&1";
  if (std::system(command.c_str()) != 0) throw std::runtime_error("synth failed: " + command);
}

std::string AddPngPayload(const fs::path& path, const std::string& payload) {
  const std::string png = ReadBytes(path);
  const auto big_endian = [](std::uint32_t value) {
    return std::string{static_cast<char>(value >> 24), static_cast<char>(value >> 16),
                       static_cast<char>(value >> 8), static_cast<char>(value)};
  };
  const std::string chunk = "reCo" + payload;  // ancillary, private, safe to copy
  const auto crc = static_cast<std::uint32_t>(
      crc32(0L, reinterpret_cast<const Bytef*>(chunk.data()), static_cast<uInt>(chunk.size())));
  const std::string bytes = png.substr(0, png.size() - 12) +
                            big_endian(static_cast<std::uint32_t>(payload.size())) + chunk + big_endian(crc) +
                            png.substr(png.size() - 12);
  WriteBytes(path, bytes);
  return bytes;
}

std::string Capture(const std::string& command) {
  std::string output;
  FILE* pipe = popen(command.c_str(), "r");
  if (!pipe) return output;
  char buffer[4096];
  while (const std::size_t n = fread(buffer, 1, sizeof(buffer), pipe)) output.append(buffer, n);
  pclose(pipe);
  return output;
}

Cluster::Cluster(std::vector<std::string> server_flags, bool start) : server_flags_(std::move(server_flags)) {
  port_ = FreePort();
  metrics_port_ = FreePort();
  address_ = "127.0.0.1:" + std::to_string(port_);
  fs::create_directories(data_dir());
  if (start) StartServer();
}

void Cluster::UseCredentials(const ClientCredentials& credentials) {
  credentials_ = credentials;
  if (server_) stub_ = v1::JobService::NewStub(OpenChannel(address_, ChannelSecurityOf(credentials_)));
}

void Cluster::StartServer() {
  const bool first = server_starts_ == 0;
  for (int attempt = 1;; ++attempt) {
    std::vector<std::string> argv{BuiltBinary("server/endorecon-server"),
                                  "--listen",
                                  address_,
                                  "--data-dir",
                                  data_dir().string(),
                                  "--metrics-port",
                                  std::to_string(metrics_port_),
                                  "--heartbeat-ms",
                                  "300"};
    // Short leases, unless the test sets its own (the server refuses a flag given twice).
    if (std::find(server_flags_.begin(), server_flags_.end(), "--lease-ttl-ms") == server_flags_.end())
      argv.insert(argv.end(), {"--lease-ttl-ms", std::to_string(3000 * kSlowdown)});
    argv.insert(argv.end(), server_flags_.begin(), server_flags_.end());
    const fs::path log = dir_ / ("server-" + std::to_string(server_starts_++) + ".log");
    server_ = std::make_unique<Process>(argv, log);
    // A channel that tried before the port was open backs off for seconds: wait for the port first.
    const auto refused = [&] { return ReadBytes(log).find("cannot listen") != std::string::npos; };
    WaitUntil([&] { return PortOpen(port_) || refused(); }, std::chrono::seconds(20));
    // FreePort's port is free when asked, not when the server binds: another test's outgoing
    // connection may take it meanwhile (ctest runs tests in parallel). On the first start no one
    // holds the address yet, so the server gets fresh ports; a restart must keep its address.
    if (!first || attempt == 3 || PortOpen(port_) || !refused()) break;
    server_->Wait();
    port_ = FreePort();
    metrics_port_ = FreePort();
    address_ = "127.0.0.1:" + std::to_string(port_);
  }
  stub_ = v1::JobService::NewStub(OpenChannel(address_, ChannelSecurityOf(credentials_)));
  const bool up = WaitUntil(
      [&] {
        grpc::ClientContext context;
        context.set_deadline(std::chrono::system_clock::now() + std::chrono::milliseconds(500));
        v1::ListWorkersResponse response;
        // Any answer means up: a client token may not list workers (PERMISSION_DENIED).
        const auto code = stub_->ListWorkers(&context, {}, &response).error_code();
        return code != grpc::StatusCode::UNAVAILABLE && code != grpc::StatusCode::DEADLINE_EXCEEDED;
      },
      std::chrono::seconds(20));
  if (!up) throw std::runtime_error("server did not come up:\n" + ServerLog());
}

void Cluster::KillServer(int signal) {
  server_->Signal(signal);
  server_->Wait();
}

Process& Cluster::StartWorker(const std::string& id, std::vector<std::string> flags) {
  // The worker picks its metrics port: a port from FreePort() could be taken by another process
  // before the worker bound it, and the worker then exited (a CI run lost a test so, 2026-12-06).
  std::vector<std::string> argv{BuiltBinary("worker/runtime/endorecon-worker"),
                                "serve",
                                "--server",
                                address_,
                                "--id",
                                id,
                                "--metrics-port",
                                "0",
                                "--work-dir",
                                (dir_ / ("work-" + id)).string(),
                                "--threads",
                                "1"};
  if (std::find(flags.begin(), flags.end(), "--lease-wait") == flags.end())
    argv.insert(argv.end(), {"--lease-wait", "2"});
  argv.insert(argv.end(), flags.begin(), flags.end());
  workers_.emplace_back(id, std::make_unique<Process>(argv, dir_ / ("worker-" + id + ".log")));
  return *workers_.back().second;
}

void Cluster::StopWorker(const std::string& id, int signal) {
  for (auto& [name, process] : workers_) {
    if (name == id) {
      process->Signal(signal);
      process->Wait();
    }
  }
}

int Cluster::worker_metrics_port(const std::string& id) const {
  static constexpr std::string_view kSaid = "metrics on port ";
  for (const auto& [name, process] : workers_) {
    if (name != id) continue;
    const std::string log = process->Log();
    const auto at = log.find(kSaid);
    if (at != std::string::npos) return std::atoi(log.c_str() + at + kSaid.size());
  }
  return 0;
}

v1::Job Cluster::Job(const std::string& id) {
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(10));
  v1::GetJobRequest request;
  request.set_id(id);
  v1::Job job;
  ThrowIfFailed(stub_->Get(&context, request, &job), "get " + id);
  return job;
}

std::string Cluster::Submit(const fs::path& clip, const std::vector<std::string>& flags) {
  std::vector<std::string> args = credentials_.CliFlags();
  args.insert(args.end(), {"--json", "submit", clip.string()});
  args.insert(args.end(), flags.begin(), flags.end());
  const auto result = RunCli(address_, args);
  if (result.exit_code != 0) throw std::runtime_error("submit failed: " + result.err);
  const auto key = result.out.find("\"id\":\"");
  return result.out.substr(key + 6, 12);
}

v1::Job Cluster::WaitForState(const std::string& id, v1::JobState state, std::chrono::seconds limit) {
  v1::Job job;
  WaitUntil(
      [&] {
        try {
          job = Job(id);
        } catch (const std::exception&) {
          return false;
        }
        return job.state() == state;
      },
      limit);
  return job;
}

ClientCredentials MakeCredentials(const Cluster& cluster, const std::string& ca_file, const std::string& role,
                                  const std::string& tenant, const std::string& name) {
  const auto token = CreateToken(cluster.data_dir(), role, tenant, name);
  return {ca_file, WriteTokenFile(cluster.path(name + ".token"), token).string()};
}

std::string Cluster::ServerLog() const {
  std::string log;
  for (int i = 0; i < server_starts_; ++i) log += ReadBytes(dir_ / ("server-" + std::to_string(i) + ".log"));
  return log;
}

}  // namespace endorecon::testing
