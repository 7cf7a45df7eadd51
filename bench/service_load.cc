// service_load: the service under many clients at once, against a real endorecon-server over
// loopback. Each round: --clients clients (one channel each) upload --upload-mib MiB between them
// at the same time, then submit --jobs jobs in all, then --watchers watch queued jobs while every
// client keeps calling each unary RPC of the job API and a few in-process workers lease, complete
// and fail jobs through the worker API; then everything still queued is cancelled. Reports errors,
// p50/p99 latency of each unary RPC as the clients saw it (target p99 < 50 ms) beside the bound the
// server's own endorecon_rpc_seconds histogram puts on its p99 (the server's work without the
// clients' and the kernel's scheduling, which on a small machine running both is most of a call's
// time), and the server's memory, file descriptors
// and threads at the peak of the round and after it; later rounds must not grow what is held after
// them (a leak of memory, descriptors or threads shows as growth). Descriptors and threads must come
// back exactly; the memory after the last round may not exceed by 10% the larger of the first two
// rounds' (the first two fill what a running server keeps: the job store's page cache, glibc's
// arenas, the watch entries of the jobs settled in the last 60 s, which span two rounds).
// With --pace-ms P each client makes a call every P ms (clients spread over the interval, latency
// counted from when a call was due, each call issued when due whether or not the client's previous
// one has returned) instead of back to back: the latency at a stated offered load rather than at
// saturation, where a closed loop of 100 clients measures the queue they make. The job API's calls
// and the watches are asynchronous (gRPC's callback API), so the load holds no thread per client;
// the upload and the in-process workers use a thread each.
// Usage: service_load [--clients N] [--jobs N] [--upload-mib N] [--watchers N] [--rounds N]
//                     [--pace-ms P] [--dir D]
#include <signal.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <random>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "common/file_upload.h"
#include "common/grpc_status.h"
#include "common/manifest.h"
#include "common/transport_security.h"
#include "endorecon/v1/job_service.grpc.pb.h"
#include "endorecon/v1/worker_service.grpc.pb.h"
#include "tests/integration/service_harness.h"

namespace {

namespace fs = std::filesystem;
using namespace endorecon;
using namespace endorecon::testing;
using Clock = std::chrono::steady_clock;
using std::chrono::milliseconds;

struct Flags {
  int clients = 100;
  int jobs = 1000;
  int upload_mib = 1024;
  int watchers = 100;
  int rounds = 3;
  int calls_per_client = 20;  // of each job-API unary RPC, per client and round, under the watchers
  int workers = 4;
  int pace_ms = 0;  // each client's interval between its calls; 0: back to back (saturating)
  std::string dir;
};

// What a process holds, from /proc/<pid>/: resident memory, open file descriptors, threads.
struct ProcessUsage {
  long rss_kib = -1;
  int fds = -1;
  int threads = -1;
};

ProcessUsage UsageOf(pid_t pid) {
  const fs::path proc = "/proc/" + std::to_string(pid);
  ProcessUsage usage;
  std::ifstream status(proc / "status");
  std::string line;
  while (std::getline(status, line)) {
    if (line.starts_with("VmRSS:")) usage.rss_kib = std::stol(line.substr(6));
    if (line.starts_with("Threads:")) usage.threads = std::stoi(line.substr(8));
  }
  std::error_code error;
  int fds = 0;
  for (auto it = fs::directory_iterator(proc / "fd", error); !error && it != fs::directory_iterator();
       it.increment(error)) {
    ++fds;
  }
  if (!error) usage.fds = fds;
  return usage;
}

double MsSince(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

std::string FormatMs(double ms) {
  char text[32];
  std::snprintf(text, sizeof text, "%g", ms);
  return text;
}

// The server's own view of its work: a histogram's buckets by the value of one label (cumulative
// counts by upper bound in seconds; "" for a histogram without the label), scraped from its /metrics.
// endorecon_rpc_seconds by method, endorecon_store_commit_seconds (no label).
using RpcBuckets = std::map<std::string, std::map<double, double>>;

RpcBuckets ScrapeBuckets(int metrics_port, const std::string& histogram, const std::string& by_label) {
  RpcBuckets buckets;
  std::istringstream text(
      Capture("curl -s --max-time 5 http://127.0.0.1:" + std::to_string(metrics_port) + "/metrics"));
  const std::string prefix = histogram + "_bucket{";
  for (std::string line; std::getline(text, line);) {
    if (line.rfind(prefix, 0) != 0) continue;
    const auto label = [&](const std::string& name) {
      const auto at = line.find(name + "=\"");
      if (at == std::string::npos) return std::string();
      const auto start = at + name.size() + 2;
      return line.substr(start, line.find('"', start) - start);
    };
    const auto le = label("le");
    buckets[by_label.empty() ? std::string() : label(by_label)][le == "+Inf" ? INFINITY : std::stod(le)] =
        std::stod(line.substr(line.rfind(' ') + 1));
  }
  return buckets;
}

RpcBuckets ScrapeRpcBuckets(int metrics_port) {
  return ScrapeBuckets(metrics_port, "endorecon_rpc_seconds", "method");
}
RpcBuckets ScrapeCommitBuckets(int metrics_port) {
  return ScrapeBuckets(metrics_port, "endorecon_store_commit_seconds", "");
}

// The upper bound, in ms, of the bucket holding the quantile q of the observations between two
// scrapes (keys without any in between are left out); q = 1: the slowest one's bucket.
std::map<std::string, double> ServerQuantile(const RpcBuckets& before, const RpcBuckets& after, double q) {
  std::map<std::string, double> p99;
  for (const auto& [method, counts] : after) {
    const auto earlier = before.find(method);
    const auto count = [&](double le) {
      const double was = earlier == before.end() || !earlier->second.count(le) ? 0 : earlier->second.at(le);
      return counts.at(le) - was;
    };
    const double total = count(INFINITY);
    if (total <= 0) continue;
    for (const auto& [le, unused] : counts) {
      if (count(le) >= q * total) {
        p99[method] = le * 1000;
        break;
      }
    }
  }
  return p99;
}
std::map<std::string, double> ServerP99(const RpcBuckets& before, const RpcBuckets& after) {
  return ServerQuantile(before, after, 0.99);
}

// Observations between two scrapes under `key`.
double ObservedBetween(const RpcBuckets& before, const RpcBuckets& after, const std::string& key) {
  const auto now = after.find(key);
  if (now == after.end()) return 0;
  const auto was = before.find(key);
  return now->second.at(INFINITY) - (was == before.end() ? 0 : was->second.at(INFINITY));
}

// Latencies and errors of every RPC, from every thread.
class Calls {
 public:
  // Runs `call` (returning a grpc::Status) and records its latency under `rpc`, from `start` (when
  // the call was due: a paced client that falls behind counts its wait, so a slow server cannot hide
  // its latency by slowing the load down).
  template <typename Call>
  bool Timed(const std::string& rpc, Call&& call, Clock::time_point start = Clock::now()) {
    return Add(rpc, call(), start);
  }
  // Records a call of `rpc` that started (or was due) at `start` and has just returned `status`.
  bool Add(const std::string& rpc, const grpc::Status& status, Clock::time_point start) {
    const double ms = MsSince(start);
    std::lock_guard lock(mutex_);
    auto& record = records_[rpc];
    record.ms.push_back(ms);
    if (!status.ok()) {
      ++record.errors;
      if (record.first_error.empty())
        record.first_error = std::to_string(status.error_code()) + " " + status.error_message();
    }
    return status.ok();
  }
  void Error(const std::string& what, const std::string& message) {
    std::lock_guard lock(mutex_);
    auto& record = records_[what];
    ++record.errors;
    if (record.first_error.empty()) record.first_error = message;
  }

  // Prints one line per RPC; returns the errors in all.
  // `server_p99`: the bound the server's own histogram puts on each RPC's p99 (ServerP99).
  int Print(const std::vector<std::string>& unary, const std::map<std::string, double>& server_p99) {
    std::lock_guard lock(mutex_);
    int errors = 0;
    std::printf("  %-12s %7s %6s %9s %9s %9s %13s %s\n", "rpc", "calls", "errors", "p50 ms", "p99 ms",
                "max ms", "server p99 ms", "");
    for (auto& [rpc, record] : records_) {
      std::sort(record.ms.begin(), record.ms.end());
      const auto at = [&](double q) {
        return record.ms.empty() ? 0.0 : record.ms[static_cast<std::size_t>(q * (record.ms.size() - 1))];
      };
      const bool is_unary = std::find(unary.begin(), unary.end(), rpc) != unary.end();
      const auto server = server_p99.find(rpc);
      const std::string server_text =
          server == server_p99.end()
              ? "-"
              : (std::isinf(server->second) ? std::string("> 60000") : "<= " + FormatMs(server->second));
      std::printf("  %-12s %7zu %6d %9.2f %9.2f %9.2f %13s %s%s\n", rpc.c_str(), record.ms.size(),
                  record.errors, at(0.5), at(0.99), record.ms.empty() ? 0.0 : record.ms.back(),
                  server_text.c_str(),
                  is_unary ? (at(0.99) < 50 ? "p99 < 50 ms" : "p99 OVER 50 ms") : "(stream)",
                  record.first_error.empty() ? "" : ("  first error: " + record.first_error).c_str());
      errors += record.errors;
    }
    records_.clear();
    return errors;
  }

 private:
  struct Record {
    std::vector<double> ms;
    int errors = 0;
    std::string first_error;
  };
  std::mutex mutex_;
  std::map<std::string, Record> records_;
};

// The start offset of client `c`'s calls within the first interval, so that the clients' calls are
// not in step.
milliseconds Offset(int pace_ms, int c) { return milliseconds(pace_ms * ((c * 7919) % 1000) / 1000); }

// One call of a client: starts an asynchronous RPC, records its latency from `due` and calls `done`
// once the RPC has returned.
using Done = std::function<void()>;
using Call = std::function<void(Clock::time_point due, Done done)>;

// Runs every client's calls and returns when all have returned. With a pace, one thread issues each
// call when it is due, whether or not that client's previous call has returned (an open loop: a slow
// server cannot slow the offered load down and hide its latency), and gRPC's own threads complete
// them; without a pace, each client's next call starts as its previous one returns (a closed loop:
// the server saturated). Either way the load generator holds no thread per client: on a small machine
// running both, 100 client threads waking for each call compete with the server for its cores and
// their scheduling shows up as the server's latency (real clients run on other machines).
void Drive(std::vector<std::vector<Call>>& calls, int pace_ms) {
  std::mutex mutex;
  std::condition_variable returned;
  std::size_t pending = 0;
  for (const auto& client : calls) pending += client.size();
  const auto one_returned = [&] {
    std::lock_guard lock(mutex);
    if (--pending == 0) returned.notify_all();
  };
  if (pace_ms > 0) {
    struct Due {
      Clock::time_point at;
      std::size_t client, call;
    };
    std::vector<Due> schedule;
    const auto start = Clock::now();
    for (std::size_t c = 0; c < calls.size(); ++c) {
      for (std::size_t i = 0; i < calls[c].size(); ++i) {
        schedule.push_back({start + Offset(pace_ms, static_cast<int>(c)) + milliseconds(pace_ms) * i, c, i});
      }
    }
    std::sort(schedule.begin(), schedule.end(), [](const Due& a, const Due& b) { return a.at < b.at; });
    for (const auto& due : schedule) {
      std::this_thread::sleep_until(due.at);
      calls[due.client][due.call](due.at, one_returned);
    }
  }
  // Without a pace, each client's chain: call i, and when it returns, call i + 1 (outlives the calls).
  const std::function<void(std::size_t, std::size_t)> next = [&](std::size_t c, std::size_t i) {
    if (i == calls[c].size()) return;
    calls[c][i](Clock::now(), [&, c, i] {
      next(c, i + 1);
      one_returned();
    });
  };
  if (pace_ms == 0) {
    for (std::size_t c = 0; c < calls.size(); ++c) next(c, 0);
  }
  std::unique_lock lock(mutex);
  returned.wait(lock, [&] { return pending == 0; });
}

std::unique_ptr<grpc::ClientContext> Context(int seconds = 30) {
  return CallContext(std::chrono::seconds(seconds));
}

// Samples the server's usage every 100 ms; keeps the largest of each.
class UsageSampler {
 public:
  explicit UsageSampler(pid_t pid) : pid_(pid), thread_([this] { Loop(); }) {}
  ~UsageSampler() {
    stop_ = true;
    thread_.join();
  }
  ProcessUsage peak() {
    std::lock_guard lock(mutex_);
    return peak_;
  }

 private:
  void Loop() {
    while (!stop_) {
      const auto now = UsageOf(pid_);
      {
        std::lock_guard lock(mutex_);
        peak_.rss_kib = std::max(peak_.rss_kib, now.rss_kib);
        peak_.fds = std::max(peak_.fds, now.fds);
        peak_.threads = std::max(peak_.threads, now.threads);
      }
      std::this_thread::sleep_for(milliseconds(100));
    }
  }
  pid_t pid_;
  std::atomic<bool> stop_{false};
  std::mutex mutex_;
  ProcessUsage peak_;
  std::thread thread_;
};

void WriteRandom(const fs::path& path, std::int64_t bytes, std::uint64_t seed) {
  fs::create_directories(path.parent_path());
  std::ofstream out(path, std::ios::binary);
  std::mt19937_64 random(seed);
  std::vector<std::uint64_t> block(1 << 15);
  for (std::int64_t done = 0; done < bytes; done += static_cast<std::int64_t>(block.size() * 8)) {
    for (auto& word : block) word = random();
    const auto n = std::min<std::int64_t>(bytes - done, static_cast<std::int64_t>(block.size() * 8));
    out.write(reinterpret_cast<const char*>(block.data()), static_cast<std::streamsize>(n));
  }
}

// A Watch stream on one job, read to its end on gRPC's threads.
class Watch : public grpc::ClientReadReactor<v1::JobEvent> {
 public:
  Watch(v1::JobService::Stub& stub, const std::string& id, std::atomic<int>& events, Calls& calls)
      : context_(CallContext(std::chrono::minutes(10))), events_(events), calls_(calls) {
    request_.set_id(id);
    stub.async()->Watch(context_.get(), &request_, this);
    StartRead(&event_);
    StartCall();
  }
  void OnReadDone(bool ok) override {
    if (!ok) return;
    ++events_;
    StartRead(&event_);
  }
  void OnDone(const grpc::Status& status) override {
    if (!status.ok() && status.error_code() != grpc::StatusCode::CANCELLED)
      calls_.Error("Watch", status.error_message());
    std::lock_guard lock(mutex_);
    done_ = true;
    ended_.notify_all();
  }
  // Returns once the stream has ended.
  void Await() {
    std::unique_lock lock(mutex_);
    ended_.wait(lock, [&] { return done_; });
  }

 private:
  std::unique_ptr<grpc::ClientContext> context_;
  v1::WatchJobRequest request_;
  v1::JobEvent event_;
  std::atomic<int>& events_;
  Calls& calls_;
  std::mutex mutex_;
  std::condition_variable ended_;
  bool done_ = false;
};

class Load {
 public:
  Load(const Flags& flags, pid_t server, std::string address, int metrics_port, fs::path dir)
      : flags_(flags),
        server_(server),
        address_(std::move(address)),
        metrics_port_(metrics_port),
        dir_(std::move(dir)) {}

  // One round; returns its errors.
  int Round(int round) {
    std::printf("round %d: %d clients, %d MiB uploaded at once, %d jobs, %d watchers, %s\n", round,
                flags_.clients, flags_.upload_mib, flags_.jobs, flags_.watchers,
                flags_.pace_ms == 0
                    ? "calls back to back"
                    : ("a call every " + std::to_string(flags_.pace_ms) + " ms per client (" +
                       std::to_string(flags_.clients * 1000 / flags_.pace_ms) + " calls/s offered)")
                          .c_str());
    std::vector<std::shared_ptr<grpc::Channel>> channels;
    for (int c = 0; c < flags_.clients; ++c) channels.push_back(OpenChannel(address_));
    UsageSampler sampler(server_);
    const auto rpc_before = ScrapeRpcBuckets(metrics_port_);
    const auto commits_before = ScrapeCommitBuckets(metrics_port_);

    // Every client's clip: a file of its share of the upload, unique to the round.
    const std::int64_t share = (static_cast<std::int64_t>(flags_.upload_mib) << 20) / flags_.clients;
    std::vector<v1::Manifest> clips(static_cast<std::size_t>(flags_.clients));
    for (int c = 0; c < flags_.clients; ++c) {
      const fs::path clip = dir_ / ("round-" + std::to_string(round)) / ("client-" + std::to_string(c));
      WriteRandom(clip / "video.bin", share, static_cast<std::uint64_t>(round) * 100003 + c);
      clips[static_cast<std::size_t>(c)] = ManifestOfDirectory(clip);
    }
    // The clips on disk before any call: the kernel would otherwise write these 1 GiB back in one
    // burst some seconds later, in the middle of the round, on the disk the server's job store
    // fsyncs (real clients upload from other machines).
    ::sync();
    const auto upload_start = Clock::now();
    EachClient(
        [&](int c, v1::JobService::Stub& stub) {
          UploadCalls upload;
          upload.query = [&](grpc::ClientContext* context, const v1::Manifest& m, v1::UploadStatus* s) {
            return stub.QueryUpload(context, m, s);
          };
          upload.open = [&](grpc::ClientContext* context, v1::UploadStatus* s) {
            return stub.Upload(context, s);
          };
          const fs::path clip = dir_ / ("round-" + std::to_string(round)) / ("client-" + std::to_string(c));
          calls_.Timed("Upload", [&] {
            try {
              const auto result =
                  UploadFiles(clip, clips[static_cast<std::size_t>(c)], upload, UploadOptions{});
              return result.status.complete()
                         ? grpc::Status::OK
                         : grpc::Status(grpc::StatusCode::UNAVAILABLE, "upload incomplete");
            } catch (const endorecon::Error& e) {
              return grpc::Status(ToGrpcCode(e.code()), e.what());
            }
          });
        },
        channels);
    const double upload_s = MsSince(upload_start) / 1000;
    std::printf("  upload: %d MiB from %d clients at once in %.1f s (%.0f MiB/s)\n", flags_.upload_mib,
                flags_.clients, upload_s, flags_.upload_mib / upload_s);

    std::vector<std::unique_ptr<v1::JobService::Stub>> stubs;
    for (const auto& channel : channels) stubs.push_back(v1::JobService::NewStub(channel));
    const auto client = [&](int c) { return stubs[static_cast<std::size_t>(c)]->async(); };

    // 1,000 jobs, submitted by every client at once.
    std::mutex ids_mutex;
    std::vector<std::string> ids;
    std::vector<std::vector<Call>> submits(static_cast<std::size_t>(flags_.clients));
    for (int c = 0; c < flags_.clients; ++c) {
      for (int j = c; j < flags_.jobs; j += flags_.clients) {
        v1::SubmitRequest request;
        *request.mutable_clip() = clips[static_cast<std::size_t>(c)];
        request.mutable_options()->set_iterations(100);
        request.set_name("load-" + std::to_string(round) + "-" + std::to_string(j));
        submits[static_cast<std::size_t>(c)].push_back(Unary<v1::Job>(
            "Submit", [=](auto... call) { client(c)->Submit(call...); }, request,
            [&](const grpc::Status& status, const v1::Job& job) {
              if (status.ok()) {
                std::lock_guard lock(ids_mutex);
                ids.push_back(job.id());
              }
              return status;
            }));
      }
    }
    Drive(submits, flags_.pace_ms);

    // The workers register and start leasing first, as a cluster's workers are up before its users.
    std::atomic<bool> leasing{true};
    std::atomic<int> registered{0};
    std::vector<std::thread> workers;
    for (int w = 0; w < flags_.workers; ++w) {
      workers.emplace_back([&, w] {
        Worker(channels[static_cast<std::size_t>(w) % channels.size()], w, clips[0], leasing, registered);
      });
    }
    while (registered < flags_.workers) std::this_thread::sleep_for(milliseconds(1));
    // Watchers on queued jobs, opened over the first interval (at once when unpaced), while clients
    // call every unary RPC and the workers lease.
    std::atomic<int> watch_events{0};
    std::vector<std::unique_ptr<Watch>> watches;
    if (!ids.empty()) {
      std::vector<std::pair<milliseconds, int>> opening;
      for (int w = 0; w < flags_.watchers; ++w) opening.emplace_back(Offset(flags_.pace_ms, w), w);
      std::sort(opening.begin(), opening.end());
      const auto start = Clock::now();
      for (const auto& [offset, w] : opening) {
        std::this_thread::sleep_until(start + offset);
        watches.push_back(std::make_unique<Watch>(*stubs[static_cast<std::size_t>(w) % stubs.size()],
                                                  ids[static_cast<std::size_t>(w) % ids.size()], watch_events,
                                                  calls_));
      }
    }
    std::vector<std::vector<Call>> queries(static_cast<std::size_t>(flags_.clients));
    for (int c = 0; c < flags_.clients; ++c) {
      auto& mine = queries[static_cast<std::size_t>(c)];
      for (int i = 0; i < flags_.calls_per_client; ++i) {
        v1::GetJobRequest get;
        get.set_id(ids[static_cast<std::size_t>(c * flags_.calls_per_client + i) % ids.size()]);
        mine.push_back(Unary<v1::Job>(
            "Get", [=](auto... call) { client(c)->Get(call...); }, get));
        v1::ListJobsRequest list;
        list.set_page_size(50);
        mine.push_back(Unary<v1::ListJobsResponse>(
            "List", [=](auto... call) { client(c)->List(call...); }, list));
        mine.push_back(Unary<v1::UploadStatus>(
            "QueryUpload", [=](auto... call) { client(c)->QueryUpload(call...); },
            clips[static_cast<std::size_t>(c)]));
        mine.push_back(Unary<v1::ListWorkersResponse>(
            "ListWorkers", [=](auto... call) { client(c)->ListWorkers(call...); }, v1::ListWorkersRequest()));
      }
    }
    Drive(queries, flags_.pace_ms);
    leasing = false;
    for (auto& worker : workers) worker.join();
    const auto peak_under_load = sampler.peak();

    // Cancel what is still queued, which ends every watch.
    std::vector<std::vector<Call>> cancels(static_cast<std::size_t>(flags_.clients));
    for (std::size_t j = 0; j < ids.size(); ++j) {
      const int c = static_cast<int>(j % static_cast<std::size_t>(flags_.clients));
      v1::CancelJobRequest cancel;
      cancel.set_id(ids[j]);
      cancels[static_cast<std::size_t>(c)].push_back(Unary<v1::Job>(
          "Cancel", [=](auto... call) { client(c)->Cancel(call...); }, cancel,
          [](const grpc::Status& status, const v1::Job&) {
            // A job the workers finished first cannot be cancelled: not an error of the server.
            return status.error_code() == grpc::StatusCode::FAILED_PRECONDITION ? grpc::Status::OK : status;
          }));
    }
    Drive(cancels, flags_.pace_ms);
    for (auto& watch : watches) watch->Await();
    watches.clear();
    const auto peak = sampler.peak();
    channels.clear();
    std::this_thread::sleep_for(std::chrono::seconds(3));
    after_ = UsageOf(server_);
    std::printf("  watch events received: %d\n", watch_events.load());
    const int errors = calls_.Print({"Submit", "Get", "List", "QueryUpload", "ListWorkers", "Cancel",
                                     "Register", "Lease", "Complete", "Fail", "QueryBlobs"},
                                    ServerP99(rpc_before, ScrapeRpcBuckets(metrics_port_)));
    // The job store's commits: a slow fsync holds every writing call that waits for it.
    const auto commits_after = ScrapeCommitBuckets(metrics_port_);
    const auto commit_bound = [&](double q) {
      const auto bounds = ServerQuantile(commits_before, commits_after, q);
      return bounds.count("") ? FormatMs(bounds.at("")) : std::string("-");
    };
    std::printf("  job store commits: %.0f, p50 <= %s ms, p99 <= %s ms, slowest <= %s ms\n",
                ObservedBetween(commits_before, commits_after, ""), commit_bound(0.5).c_str(),
                commit_bound(0.99).c_str(), commit_bound(1.0).c_str());
    std::printf(
        "  server at the peak: %.1f MB resident, %d fds, %d threads (%.1f MB, %d fds, %d threads under the "
        "watchers)\n",
        peak.rss_kib / 1024.0, peak.fds, peak.threads, peak_under_load.rss_kib / 1024.0, peak_under_load.fds,
        peak_under_load.threads);
    std::printf("  server after the round (3 s idle): %.1f MB resident, %d fds, %d threads\n",
                after_.rss_kib / 1024.0, after_.fds, after_.threads);
    PrintServerWarnings();
    std::printf("  errors: %d\n", errors);
    return errors;
  }

  ProcessUsage after() const { return after_; }

 private:
  // One call of a unary RPC: `start(context, request, response, callback)` starts it asynchronously
  // (a stub's async method); `judge`, when given, sees its status and response and returns the status
  // to count. Its context, request and response live until it returns.
  template <typename Response, typename Request, typename Start>
  Call Unary(const char* rpc, Start start, const Request& request,
             std::function<grpc::Status(const grpc::Status&, const Response&)> judge = nullptr) {
    return [this, rpc, start, request, judge](Clock::time_point due, Done done) {
      struct State {
        std::unique_ptr<grpc::ClientContext> context = Context();
        Request request;
        Response response;
      };
      auto state = std::make_shared<State>();
      state->request = request;
      start(state->context.get(), &state->request, &state->response,
            std::function<void(grpc::Status)>([this, rpc, due, done, judge, state](grpc::Status status) {
              calls_.Add(rpc, judge ? judge(status, state->response) : status, due);
              done();
            }));
    };
  }

  // The server's warnings (a slow commit, a stalled stream, ...) logged since the last call.
  void PrintServerWarnings() {
    std::ifstream log(dir_ / "server.log");
    log.seekg(log_offset_);
    for (std::string line; std::getline(log, line);) {
      if (line.find("[warning]") != std::string::npos || line.find("[error]") != std::string::npos ||
          line.find("[critical]") != std::string::npos) {
        std::printf("  server: %s\n", line.c_str());
      }
      if (log.good()) log_offset_ = log.tellg();
    }
  }

  template <typename Body>
  void EachClient(Body&& body, const std::vector<std::shared_ptr<grpc::Channel>>& channels) {
    std::vector<std::thread> threads;
    for (int c = 0; c < flags_.clients; ++c) {
      threads.emplace_back([&, c] {
        auto stub = v1::JobService::NewStub(channels[static_cast<std::size_t>(c)]);
        body(c, *stub);
      });
    }
    for (auto& thread : threads) thread.join();
  }

  // A worker that leases with no wait and completes (every other job) or hands back (the rest).
  void Worker(const std::shared_ptr<grpc::Channel>& channel, int w, const v1::Manifest& result,
              const std::atomic<bool>& leasing, std::atomic<int>& registered) {
    auto stub = v1::WorkerService::NewStub(channel);
    const std::string id = "load-worker-" + std::to_string(w);
    v1::RegisterRequest reg;
    reg.set_worker_id(id);
    reg.add_devices("cpu");
    v1::RegisterResponse response;
    calls_.Timed("Register", [&] { return stub->Register(Context().get(), reg, &response); });
    ++registered;
    for (int n = 0; leasing; ++n) {
      v1::LeaseRequest request;
      request.set_worker_id(id);
      request.set_wait_ms(0);
      v1::LeaseResponse lease;
      if (!calls_.Timed("Lease", [&] { return stub->Lease(Context().get(), request, &lease); }) ||
          !lease.has_job()) {
        std::this_thread::sleep_for(milliseconds(20));
        continue;
      }
      v1::UploadStatus status;
      calls_.Timed("QueryBlobs", [&] { return stub->QueryBlobs(Context().get(), result, &status); });
      v1::Job job;
      if (n % 2 == 0) {
        v1::CompleteRequest complete;
        complete.set_lease_id(lease.lease_id());
        *complete.mutable_result() = result;
        calls_.Timed("Complete", [&] { return stub->Complete(Context().get(), complete, &job); });
      } else {
        v1::FailRequest fail;
        fail.set_lease_id(lease.lease_id());
        fail.set_reason("service_load hands it back");
        fail.set_retry(true);
        fail.set_release(true);
        calls_.Timed("Fail", [&] { return stub->Fail(Context().get(), fail, &job); });
      }
      std::this_thread::sleep_for(milliseconds(50));
    }
  }

  Flags flags_;
  pid_t server_;
  std::string address_;
  int metrics_port_;
  fs::path dir_;
  std::streamoff log_offset_ = 0;
  Calls calls_;
  ProcessUsage after_;
};

}  // namespace

int main(int argc, char** argv) {
  Flags flags;
  CLI::App app{"service_load: many clients, queued jobs, a large concurrent upload and watchers at once"};
  app.add_option("--clients", flags.clients, "concurrent clients, one channel each")->capture_default_str();
  app.add_option("--jobs", flags.jobs, "jobs queued each round")->capture_default_str();
  app.add_option("--upload-mib", flags.upload_mib, "MiB uploaded by all clients at once")
      ->capture_default_str();
  app.add_option("--watchers", flags.watchers, "concurrent Watch streams")->capture_default_str();
  app.add_option("--rounds", flags.rounds, "rounds (the last must not grow what the first two left)")
      ->capture_default_str();
  app.add_option("--calls", flags.calls_per_client, "calls of each unary RPC per client and round")
      ->capture_default_str();
  app.add_option("--workers", flags.workers, "in-process workers leasing through the worker API")
      ->capture_default_str();
  app.add_option("--pace-ms", flags.pace_ms,
                 "each client's interval between its calls (0: back to back, the server saturated)")
      ->capture_default_str();
  app.add_option("--dir", flags.dir, "scratch folder (default: a new one in $TMPDIR)");
  std::string server_binary = BuiltBinary("server/endorecon-server");
  app.add_option("--server-binary", server_binary,
                 "the endorecon-server to load (a baseline build's, to compare)")
      ->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  signal(SIGPIPE, SIG_IGN);

  const fs::path dir = flags.dir.empty()
                           ? fs::temp_directory_path() / ("endorecon-load-" + std::to_string(getpid()))
                           : fs::path(flags.dir);
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string address = "127.0.0.1:" + std::to_string(FreePort());
  const int metrics_port = FreePort();
  Process server({server_binary, "--listen", address, "--data-dir", (dir / "data").string(), "--metrics-port",
                  std::to_string(metrics_port)},
                 dir / "server.log");
  for (int i = 0; i < 200 && !OpenChannel(address)->WaitForConnected(std::chrono::system_clock::now() +
                                                                     std::chrono::milliseconds(50));
       ++i) {
  }
  const auto idle = UsageOf(server.pid());
  std::printf("server idle: %.1f MB resident, %d fds, %d threads\n", idle.rss_kib / 1024.0, idle.fds,
              idle.threads);
  Load load(flags, server.pid(), address, metrics_port, dir);
  int errors = 0;
  std::vector<ProcessUsage> after;
  for (int round = 1; round <= flags.rounds; ++round) {
    errors += load.Round(round);
    after.push_back(load.after());
  }
  bool grew = false;
  if (after.size() >= 2) {
    const auto& first = after.front();
    const auto& last = after.back();
    const long settled_kib = after.size() >= 3 ? std::max(after[0].rss_kib, after[1].rss_kib) : first.rss_kib;
    grew = last.fds > first.fds || last.threads > first.threads || last.rss_kib > settled_kib * 11 / 10;
    std::printf("after rounds 1-%d -> after round %zu: %.1f -> %.1f MB, %d -> %d fds, %d -> %d threads: %s\n",
                after.size() >= 3 ? 2 : 1, after.size(), settled_kib / 1024.0, last.rss_kib / 1024.0,
                first.fds, last.fds, first.threads, last.threads, grew ? "GROWTH" : "no growth");
  }
  server.Signal(SIGTERM);
  server.Wait();
  fs::remove_all(dir);
  std::printf("errors=%d growth=%s\n", errors, grew ? "yes" : "no");
  return errors == 0 && !grew ? 0 : 1;
}
