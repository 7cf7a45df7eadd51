// service_bench: the service's numbers, against a real endorecon-server over loopback.
//   1. upload throughput (endorecon's resumable upload) against a plain copy of the same bytes on
//      the same disk (read, write, fsync): the ratio, target >= 0.5; then the same file downloaded
//      as a worker downloads a clip (GetBlobs: hashed on the server's side as it is sent, verified
//      and synced on the receiver's), with the server's CPU time per GiB sent;
//   2. submit-to-start latency with an idle worker long-polling: target < 100 ms;
//   3. server resident memory with 1,000 queued jobs and 100 concurrent watchers: target < 200 MB.
// Usage: service_bench [--upload-mib N] [--jobs N] [--watchers N] [--dir SCRATCH] [--server BINARY]
#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "common/file_download.h"
#include "common/file_upload.h"
#include "common/grpc_status.h"
#include "common/manifest.h"
#include "common/transport_security.h"
#include "endorecon/v1/job_service.grpc.pb.h"
#include "endorecon/v1/worker_service.grpc.pb.h"

namespace {
namespace fs = std::filesystem;
using namespace endorecon;
using Clock = std::chrono::steady_clock;

double Seconds(Clock::time_point since) {
  return std::chrono::duration<double>(Clock::now() - since).count();
}

pid_t StartServer(const std::string& binary, const fs::path& data, int port, const fs::path& log) {
  // Made before fork: the child of a threaded process may only call async-signal-safe functions.
  const std::string listen = "127.0.0.1:" + std::to_string(port);
  const pid_t pid = fork();
  if (pid == 0) {
    const int fd = ::open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    dup2(fd, STDOUT_FILENO);
    dup2(fd, STDERR_FILENO);
    execl(binary.c_str(), binary.c_str(), "--listen", listen.c_str(), "--data-dir", data.c_str(),
          "--metrics-port", "-1", static_cast<char*>(nullptr));
    _exit(127);
  }
  return pid;
}

// The CPU time (user + system) `pid` has used, in seconds.
double CpuSeconds(pid_t pid) {
  std::ifstream stat("/proc/" + std::to_string(pid) + "/stat");
  std::string text((std::istreambuf_iterator<char>(stat)), std::istreambuf_iterator<char>());
  std::istringstream fields(text.substr(text.rfind(')') + 2));  // after the command's name
  std::string field;
  double ticks = 0;
  for (int i = 3; i <= 15 && fields >> field; ++i) {
    if (i == 14 || i == 15) ticks += std::stod(field);  // utime, stime
  }
  return ticks / double(sysconf(_SC_CLK_TCK));
}

long RssKiB(pid_t pid) {
  std::ifstream status("/proc/" + std::to_string(pid) + "/status");
  std::string line;
  while (std::getline(status, line)) {
    if (line.rfind("VmRSS:", 0) == 0) return std::stol(line.substr(6));
  }
  return -1;
}

void WriteRandom(const fs::path& path, std::int64_t bytes) {
  std::ofstream out(path, std::ios::binary);
  std::mt19937_64 random(1);
  std::vector<std::uint64_t> block(1 << 17);
  for (std::int64_t done = 0; done < bytes; done += std::int64_t(block.size() * 8)) {
    for (auto& word : block) word = random();
    out.write(reinterpret_cast<const char*>(block.data()), std::streamsize(block.size() * 8));
  }
}

// Reads `from`, writes `to`, fsyncs: what the server's blob store does, without the network.
double PlainCopySeconds(const fs::path& from, const fs::path& to) {
  const auto start = Clock::now();
  const int in = ::open(from.c_str(), O_RDONLY);
  const int out = ::open(to.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  std::vector<char> buffer(4 << 20);
  ssize_t n = 0;
  while ((n = ::read(in, buffer.data(), buffer.size())) > 0) {
    if (::write(out, buffer.data(), std::size_t(n)) != n) break;
  }
  ::fdatasync(out);
  ::close(in);
  ::close(out);
  return Seconds(start);
}

UploadCalls CallsOf(v1::JobService::Stub& stub) {
  UploadCalls calls;
  calls.query = [&](grpc::ClientContext* c, const v1::Manifest& m, v1::UploadStatus* s) {
    return stub.QueryUpload(c, m, s);
  };
  calls.open = [&](grpc::ClientContext* c, v1::UploadStatus* s) { return stub.Upload(c, s); };
  return calls;
}

}  // namespace

int main(int argc, char** argv) {
  int upload_mib = 512, jobs = 1000, watchers = 100;
  fs::path scratch = fs::temp_directory_path() / ("endorecon-service-bench-" + std::to_string(getpid()));
  CLI::App app{"service_bench: a large upload, many queued jobs and watchers against one server"};
  app.add_option("--upload-mib", upload_mib, "the upload's size, MiB")->capture_default_str();
  app.add_option("--jobs", jobs, "jobs queued")->capture_default_str();
  app.add_option("--watchers", watchers, "watch streams")->capture_default_str();
  app.add_option("--dir", scratch, "scratch folder")->capture_default_str();
  std::string server_binary = std::string(ENDORECON_BINARY_DIR) + "/server/endorecon-server";
  app.add_option("--server", server_binary, "the server binary (another build, to compare)")
      ->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  fs::create_directories(scratch / "clip");
  const int port = 20000 + getpid() % 20000;
  const std::string address = "127.0.0.1:" + std::to_string(port);
  const pid_t server = StartServer(server_binary, scratch / "data", port, scratch / "server.log");
  auto channel = OpenChannel(address);
  channel->WaitForConnected(std::chrono::system_clock::now() + std::chrono::seconds(10));
  auto jobs_stub = v1::JobService::NewStub(channel);
  auto workers_stub = v1::WorkerService::NewStub(channel);

  {
    // A worker the server does not know is answered at once, not long-polled: register first.
    grpc::ClientContext context;
    v1::RegisterRequest request;
    request.set_worker_id("bench-worker");
    request.add_devices("cpu");
    v1::RegisterResponse response;
    ThrowIfFailed(workers_stub->Register(&context, request, &response), "register");
  }

  // 1. Upload throughput against a plain copy.
  WriteRandom(scratch / "clip" / "video.bin", std::int64_t(upload_mib) << 20);
  const auto manifest = ManifestOfDirectory(scratch / "clip");
  ::sync();  // both measurements start with no dirty pages to write back
  const double copy_s = PlainCopySeconds(scratch / "clip" / "video.bin", scratch / "copy.bin");
  fs::remove(scratch / "copy.bin");
  ::sync();
  const auto upload_start = Clock::now();
  UploadOptions options;
  UploadFiles(scratch / "clip", manifest, CallsOf(*jobs_stub), options);
  const double upload_s = Seconds(upload_start);
  const double mib = upload_mib;
  std::printf(
      "upload  %d MiB: plain copy %.2f s (%.0f MiB/s), upload over loopback %.2f s (%.0f MiB/s), ratio "
      "%.2f\n",
      upload_mib, copy_s, mib / copy_s, upload_s, mib / upload_s, copy_s / upload_s);

  // 1b. The same file downloaded as a worker downloads its clip.
  {
    v1::SubmitRequest submit;
    *submit.mutable_clip() = manifest;
    submit.mutable_options()->set_iterations(30);
    grpc::ClientContext submit_context;
    v1::Job job;
    ThrowIfFailed(jobs_stub->Submit(&submit_context, submit, &job), "submit");
    grpc::ClientContext lease_context;
    v1::LeaseRequest lease_request;
    lease_request.set_worker_id("bench-worker");
    lease_request.set_wait_ms(10000);
    v1::LeaseResponse lease;
    ThrowIfFailed(workers_stub->Lease(&lease_context, lease_request, &lease), "lease");
    v1::GetBlobsRequest get;
    get.set_lease_id(lease.lease_id());
    *get.add_files() = PendingDownloads(scratch / "download", manifest).front();
    fs::create_directories(scratch / "download");
    ::sync();
    const double server_cpu_before = CpuSeconds(server);
    const auto download_start = Clock::now();
    grpc::ClientContext get_context;
    auto reader = workers_stub->GetBlobs(&get_context, get);
    ReceiveFiles(*reader, scratch / "download");
    SyncFolder(scratch / "download");
    const double download_s = Seconds(download_start);
    const double server_cpu_s = CpuSeconds(server) - server_cpu_before;
    std::printf(
        "download %d MiB (GetBlobs, hashed by both ends, synced): %.2f s (%.0f MiB/s), ratio to the "
        "plain copy %.2f; server CPU %.2f s (%.2f s per GiB sent)\n",
        upload_mib, download_s, mib / download_s, copy_s / download_s, server_cpu_s,
        server_cpu_s / (mib / 1024));
    fs::remove_all(scratch / "download");
    grpc::ClientContext fail_context;
    v1::FailRequest fail;
    fail.set_lease_id(lease.lease_id());
    fail.set_reason("benchmark");
    v1::Job failed;
    workers_stub->Fail(&fail_context, fail, &failed);
  }

  // 2. Submit-to-start latency: an idle "worker" long-polls Lease, the client submits.
  v1::SubmitRequest submit;
  *submit.mutable_clip() = manifest;
  submit.mutable_options()->set_iterations(30);
  std::vector<double> latencies;
  for (int i = 0; i < 20; ++i) {
    Clock::time_point submitted;
    v1::LeaseResponse lease;
    std::thread worker([&] {
      grpc::ClientContext context;
      context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(30));
      v1::LeaseRequest request;
      request.set_worker_id("bench-worker");
      request.set_wait_ms(20000);
      workers_stub->Lease(&context, request, &lease);
      latencies.push_back(Seconds(submitted) * 1000);
    });
    std::this_thread::sleep_for(std::chrono::milliseconds(100));  // the worker is waiting, idle
    submitted = Clock::now();
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(10));
    v1::Job job;
    ThrowIfFailed(jobs_stub->Submit(&context, submit, &job), "submit");
    worker.join();
    grpc::ClientContext fail_context;
    fail_context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(10));
    v1::FailRequest fail;
    fail.set_lease_id(lease.lease_id());
    fail.set_reason("benchmark");
    v1::Job failed;
    workers_stub->Fail(&fail_context, fail, &failed);
  }
  std::sort(latencies.begin(), latencies.end());
  std::printf("latency submit-to-start with an idle worker, 20 runs: median %.1f ms, max %.1f ms\n",
              latencies[latencies.size() / 2], latencies.back());

  // 3. Server memory with many queued jobs and watchers.
  const long rss_idle = RssKiB(server);
  for (int i = 0; i < jobs; ++i) {
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(10));
    v1::Job job;
    ThrowIfFailed(jobs_stub->Submit(&context, submit, &job), "submit");
  }
  v1::ListJobsRequest list;
  list.add_states(v1::QUEUED);
  list.set_page_size(watchers);
  v1::ListJobsResponse queued;
  {
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(10));
    ThrowIfFailed(jobs_stub->List(&context, list, &queued), "list");
  }
  std::vector<std::unique_ptr<grpc::ClientContext>> contexts;
  std::vector<std::unique_ptr<grpc::ClientReader<v1::JobEvent>>> streams;
  for (int i = 0; i < watchers; ++i) {
    contexts.push_back(std::make_unique<grpc::ClientContext>());
    contexts.back()->set_deadline(std::chrono::system_clock::now() + std::chrono::minutes(5));
    v1::WatchJobRequest watch;
    watch.set_id(queued.jobs(i % queued.jobs_size()).id());
    watch.set_previews(true);
    streams.push_back(jobs_stub->Watch(contexts.back().get(), watch));
    v1::JobEvent first;
    streams.back()->Read(&first);
  }
  std::this_thread::sleep_for(std::chrono::seconds(2));
  const long rss_loaded = RssKiB(server);
  std::printf("memory  server RSS: %.1f MB idle, %.1f MB with %d queued jobs and %d watchers\n",
              rss_idle / 1024.0, rss_loaded / 1024.0, jobs, watchers);
  for (auto& context : contexts) context->TryCancel();
  for (auto& stream : streams) stream->Finish();
  kill(server, SIGTERM);
  waitpid(server, nullptr, 0);
  fs::remove_all(scratch);
  return 0;
}
