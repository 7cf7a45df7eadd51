// fault_campaign: kill -9 at random moments of every phase of the service's work, restart the
// victim, and count what was lost or corrupted. A real endorecon-server, --workers workers and
// --clients clients (the endorecon CLI) on loopback; each client submits clips of its own (a tiny
// synthetic clip plus a few MiB of padding, so uploads take a while), waits for the job, fetches the
// results, and every fifth job is cancelled once it runs. Meanwhile kills go round the phases:
//   upload            a client while its clip's bytes arrive (a partial file of it exists)
//   submit            a client once its clip is stored, around the Submit call
//   lease             a worker as a job folder appears in its scratch (lease granted, clip download)
//   progress          a worker while it trains and reports
//   checkpoint-upload a worker just after it wrote a checkpoint (upload and report)
//   result-upload     a worker once report.html is written (results upload, Complete)
//   fetch             a client while it downloads results
//   server-write      the server while it stores an upload, a submit or results
// Victims restart at once (a killed client runs its command again). At the end: every submitted
// job reached its intended state (SUCCEEDED, or CANCELLED when its cancel was accepted), every
// fetched file and every blob matches its SHA-256, no file is left outside the partial area (the
// server's partial/, nothing in the workers' scratch), each resumed run started at >= 90% of the
// iteration of the checkpoint its job held when its worker was killed, and the job store passes
// SQLite's integrity check. Prints the counts; the last line has lost=L corrupt=C (exit 0 when both
// are 0 and every other check passed).
// Usage: fault_campaign [--kills N] [--workers N] [--clients N] [--iterations N] [--seed S] [--dir D]
#include <signal.h>
#include <sqlite3.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <random>
#include <regex>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "common/manifest.h"
#include "common/sha256.h"
#include "common/transport_security.h"
#include "endorecon/v1/job_service.grpc.pb.h"
#include "tests/integration/service_harness.h"
#include "worker/engine/train/checkpoint.h"

namespace {

namespace fs = std::filesystem;
using namespace endorecon;
using namespace endorecon::testing;
using Clock = std::chrono::steady_clock;
using std::chrono::milliseconds;

struct Flags {
  int kills = 100;
  int workers = 2;
  int clients = 3;
  int iterations = 150;
  std::uint64_t seed = 1;
  std::string dir;
  double phase_wait_s = 60;  // a phase not seen within this is skipped for now
  double drain_s = 600;      // after the last kill, jobs must be done and fetched within this
  int pad_mib = 4;
};

enum class Phase {
  kUpload,
  kSubmit,
  kLease,
  kProgress,
  kCheckpointUpload,
  kResultUpload,
  kFetch,
  kServerWrite
};
constexpr Phase kPhases[] = {Phase::kUpload,   Phase::kSubmit,           Phase::kLease,
                             Phase::kProgress, Phase::kCheckpointUpload, Phase::kResultUpload,
                             Phase::kFetch,    Phase::kServerWrite};

const char* Name(Phase phase) {
  switch (phase) {
    case Phase::kUpload:
      return "upload";
    case Phase::kSubmit:
      return "submit";
    case Phase::kLease:
      return "lease";
    case Phase::kProgress:
      return "progress";
    case Phase::kCheckpointUpload:
      return "checkpoint-upload";
    case Phase::kResultUpload:
      return "result-upload";
    case Phase::kFetch:
      return "fetch";
    case Phase::kServerWrite:
      return "server-write";
  }
  return "?";
}

bool IsJobFolder(const fs::path& path) {
  const std::string name = path.filename().string();
  return name.size() == 12 && name.find_first_not_of("0123456789abcdef") == std::string::npos;
}

// Job folders in a worker's scratch.
std::vector<fs::path> JobFolders(const fs::path& work_dir) {
  std::vector<fs::path> folders;
  std::error_code error;
  for (auto it = fs::directory_iterator(work_dir, error); !error && it != fs::directory_iterator();
       it.increment(error)) {
    if (IsJobFolder(it->path())) folders.push_back(it->path());
  }
  return folders;
}

std::int64_t UnixMs() {
  return std::chrono::duration_cast<milliseconds>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}

// One client: the state the killer reads, set by the client's own thread.
struct Client {
  enum Stage { kIdle, kSubmitting, kFetching };
  std::mutex mutex;
  Stage stage = kIdle;
  Process* cli = nullptr;
  std::vector<std::string> digests;  // of the clip being submitted
  fs::path fetch_dir;
  std::thread thread;
};

// One submission and what became of it.
struct Submission {
  std::string name;
  std::string job_id;
  v1::JobState intent = v1::SUCCEEDED;
  v1::JobState state = v1::JOB_STATE_UNSPECIFIED;
  bool fetched = false;
  int corrupt_files = 0;
  int leftover_parts = 0;
};

struct KillRecord {
  Phase phase;
  std::string victim;
  std::string job_id;             // a worker's job, when it had one
  int checkpoint_iteration = -1;  // the iteration of the checkpoint the server held for it then
  std::int64_t unix_ms = 0;
};

class Campaign {
 public:
  explicit Campaign(const Flags& flags) : flags_(flags), random_(flags.seed) {
    dir_ = flags.dir.empty() ? fs::temp_directory_path() / ("endorecon-campaign-" + std::to_string(getpid()))
                             : fs::path(flags.dir);
    fs::remove_all(dir_);
    fs::create_directories(dir_ / "logs");
    data_ = dir_ / "data";
    port_ = FreePort();
    address_ = "127.0.0.1:" + std::to_string(port_);
  }

  int Run() {
    StartServer();
    for (int w = 0; w < flags_.workers; ++w) {
      work_dirs_.push_back(dir_ / ("worker-" + std::to_string(w)));
      workers_.emplace_back();
      StartWorker(w);
    }
    stub_ = v1::JobService::NewStub(OpenChannel(address_));
    clients_ = std::vector<Client>(static_cast<std::size_t>(flags_.clients));
    for (std::size_t c = 0; c < clients_.size(); ++c) {
      clients_[c].thread = std::thread([this, c] { ClientLoop(clients_[c], static_cast<int>(c)); });
    }
    const auto start = Clock::now();
    KillRound();
    stop_submitting_ = true;
    std::printf("kills done after %.0f s; draining\n", Seconds(start));
    std::fflush(stdout);
    const auto drain_deadline = Clock::now() + milliseconds(static_cast<std::int64_t>(flags_.drain_s * 1000));
    while (Clock::now() < drain_deadline && active_clients_ > 0)
      std::this_thread::sleep_for(milliseconds(200));
    give_up_ = true;
    for (auto& client : clients_) client.thread.join();
    return Report(Seconds(start));
  }

 private:
  static double Seconds(Clock::time_point since) {
    return std::chrono::duration<double>(Clock::now() - since).count();
  }

  // --- the cluster ----------------------------------------------------------------------------
  void StartServer() {
    server_ = std::make_unique<Process>(
        std::vector<std::string>{BuiltBinary("server/endorecon-server"), "--listen", address_, "--data-dir",
                                 data_.string(), "--metrics-port", "-1", "--lease-ttl-ms", "3000",
                                 "--heartbeat-ms", "500", "--max-attempts", "1000", "--min-free-bytes", "0"},
        dir_ / "logs/server.log");
    for (int i = 0; i < 200 && !PortOpen(port_); ++i) std::this_thread::sleep_for(milliseconds(50));
  }

  void StartWorker(int w) {
    workers_[static_cast<std::size_t>(w)] =
        std::make_unique<Process>(std::vector<std::string>{BuiltBinary("worker/runtime/endorecon-worker"),
                                                           "serve",
                                                           "--server",
                                                           address_,
                                                           "--devices",
                                                           "cpu",
                                                           "--threads",
                                                           "1",
                                                           "--id",
                                                           "worker-" + std::to_string(w),
                                                           "--work-dir",
                                                           work_dirs_[static_cast<std::size_t>(w)].string(),
                                                           "--metrics-port",
                                                           "-1",
                                                           "--checkpoint-interval",
                                                           "0.5",
                                                           "--preview-interval",
                                                           "5",
                                                           "--lease-wait",
                                                           "2",
                                                           "--timeout",
                                                           "10"},
                                  dir_ / "logs" / ("worker-" + std::to_string(w) + ".log"));
  }

  std::optional<v1::Job> GetJob(const std::string& id) {
    v1::GetJobRequest request;
    request.set_id(id);
    v1::Job job;
    auto context = CallContext(milliseconds(3000));
    if (!stub_->Get(context.get(), request, &job).ok()) return std::nullopt;
    return job;
  }

  // Every job on the server; nullopt while it cannot be reached.
  std::optional<std::vector<v1::Job>> ListJobs() {
    v1::ListJobsRequest request;
    request.set_page_size(1000);
    v1::ListJobsResponse response;
    auto context = CallContext(milliseconds(5000));
    if (!stub_->List(context.get(), request, &response).ok()) return std::nullopt;
    return std::vector<v1::Job>(response.jobs().begin(), response.jobs().end());
  }

  // The iteration of the checkpoint the server holds for `job_id` (-1: none, or unreadable).
  int CheckpointIteration(const std::string& job_id) {
    const auto job = GetJob(job_id);
    if (!job || job->checkpoint().sha256().size() != 64) return -1;
    const auto& sha = job->checkpoint().sha256();
    try {
      return train::ReadCheckpointIteration(data_ / "blobs" / sha.substr(0, 2) / sha);
    } catch (const std::exception&) {
      return -1;
    }
  }

  // --- clients --------------------------------------------------------------------------------
  int RunCli(Client& client, Client::Stage stage, const std::vector<std::string>& args, const fs::path& log) {
    std::vector<std::string> argv{BuiltBinary("client/endorecon"), "--server", address_, "--timeout", "10"};
    argv.insert(argv.end(), args.begin(), args.end());
    Process process(argv, log);
    {
      std::lock_guard lock(client.mutex);
      client.cli = &process;
      client.stage = stage;
    }
    const int code = process.Wait();
    std::lock_guard lock(client.mutex);
    client.cli = nullptr;
    client.stage = Client::kIdle;
    return code;
  }

  void MakeClip(const fs::path& clip, int n) {
    Process synth({BuiltBinary("worker/runtime/endorecon-worker"), "synth", clip.string(), "--frames", "8",
                   "--width", "32", "--height", "24", "--seed", std::to_string(n + 1)},
                  dir_ / "logs/synth.log");
    synth.Wait();
    // Padding the loaders ignore, unique to the clip, so every upload sends megabytes.
    fs::create_directories(clip / "extra");
    std::mt19937_64 bytes(static_cast<std::uint64_t>(n) * 7919 + flags_.seed);
    std::vector<std::uint64_t> block(static_cast<std::size_t>(flags_.pad_mib) << 17);
    for (auto& word : block) word = bytes();
    std::ofstream(clip / "extra/pad.bin", std::ios::binary)
        .write(reinterpret_cast<const char*>(block.data()), static_cast<std::streamsize>(block.size() * 8));
  }

  std::optional<std::string> JobNamed(const std::string& name) {
    const auto jobs = ListJobs();
    if (!jobs) return std::nullopt;
    for (const auto& job : *jobs) {
      if (job.name() == name) return job.id();
    }
    return std::string();
  }

  // Polls until the job is terminal (or the campaign gives up); the last state seen.
  v1::JobState WaitTerminal(const std::string& id, const std::function<void(const v1::Job&)>& on_running) {
    while (!give_up_) {
      if (const auto job = GetJob(id)) {
        if (job->state() == v1::SUCCEEDED || job->state() == v1::FAILED || job->state() == v1::CANCELLED)
          return job->state();
        if (job->state() == v1::RUNNING && on_running) on_running(*job);
      }
      std::this_thread::sleep_for(milliseconds(250));
    }
    const auto job = GetJob(id);
    return job ? job->state() : v1::JOB_STATE_UNSPECIFIED;
  }

  void ClientLoop(Client& client, int c) {
    ++active_clients_;
    while (!stop_submitting_ && !give_up_) {
      const int n = next_submission_++;
      Submission submission;
      submission.name = "campaign-" + std::to_string(n);
      const fs::path clip = dir_ / "clips" / submission.name;
      MakeClip(clip, n);
      const auto manifest = ManifestOfDirectory(clip);
      {
        std::lock_guard lock(client.mutex);
        client.digests.clear();
        for (const auto& file : manifest.files()) client.digests.push_back(file.sha256());
      }
      const fs::path log = dir_ / "logs" / ("client-" + std::to_string(c) + ".log");
      // A killed submit may or may not have reached Submit: the job's name tells, once the server
      // answers (a List refused while it restarts is asked again, not taken for "no such job").
      while (!give_up_ && submission.job_id.empty()) {
        RunCli(client, Client::kSubmitting,
               {"submit", clip.string(), "--name", submission.name, "--iterations",
                std::to_string(flags_.iterations), "--holdout", "0"},
               log);
        auto found = JobNamed(submission.name);
        while (!found && !give_up_) {
          std::this_thread::sleep_for(milliseconds(200));
          found = JobNamed(submission.name);
        }
        if (found) submission.job_id = *found;
      }
      if (submission.job_id.empty()) break;
      bool cancel_sent = false;
      submission.state = WaitTerminal(submission.job_id, [&](const v1::Job&) {
        if (n % 5 != 4 || cancel_sent) return;
        const int code = RunCli(client, Client::kIdle, {"cancel", submission.job_id}, log);
        if (code == 0) {
          submission.intent = v1::CANCELLED;
          cancel_sent = true;
        } else if (code == 7) {
          cancel_sent = true;  // it finished first: SUCCEEDED stays the intent
        }
      });
      if (submission.state == v1::SUCCEEDED) Fetch(client, c, submission);
      std::lock_guard lock(results_mutex_);
      submissions_.push_back(submission);
    }
    --active_clients_;
  }

  void Fetch(Client& client, int c, Submission& submission) {
    const fs::path out = dir_ / "fetched" / submission.name;
    {
      std::lock_guard lock(client.mutex);
      client.fetch_dir = out;
    }
    const fs::path log = dir_ / "logs" / ("client-" + std::to_string(c) + ".log");
    while (!give_up_ && !submission.fetched) {
      submission.fetched =
          RunCli(client, Client::kFetching, {"fetch", submission.job_id, "-o", out.string()}, log) == 0;
      if (!submission.fetched) std::this_thread::sleep_for(milliseconds(200));
    }
    const auto job = GetJob(submission.job_id);
    if (!submission.fetched || !job) return;
    for (const auto& entry : job->result().files()) {
      const fs::path file = out / entry.path();
      if (!fs::is_regular_file(file) || Sha256File(file) != entry.sha256()) ++submission.corrupt_files;
    }
    std::error_code error;
    for (auto it = fs::recursive_directory_iterator(out, error);
         !error && it != fs::recursive_directory_iterator(); it.increment(error)) {
      if (it->path().extension() == ".part") ++submission.leftover_parts;
    }
  }

  // --- kills ----------------------------------------------------------------------------------
  void Pause(int max_ms) {
    std::uniform_int_distribution<int> delay(0, max_ms);
    std::this_thread::sleep_for(milliseconds(delay(random_)));
  }

  bool KillClient(Phase phase, const std::function<bool(Client&)>& in_phase, int max_delay_ms) {
    for (auto& client : clients_) {
      const Process* target = nullptr;
      {
        std::lock_guard lock(client.mutex);
        if (!client.cli || !in_phase(client)) continue;
        target = client.cli;
      }
      Pause(max_delay_ms);
      // Only the same command: if it ended meanwhile, the phase is over and nothing is killed.
      std::lock_guard lock(client.mutex);
      if (client.cli != target || !client.cli->Signal(SIGKILL)) return false;
      kills_.push_back({phase, "client", "", -1, UnixMs()});
      return true;
    }
    return false;
  }

  bool KillWorker(Phase phase, int w, int max_delay_ms) {
    Pause(max_delay_ms);
    const auto folders = JobFolders(work_dirs_[static_cast<std::size_t>(w)]);
    workers_[static_cast<std::size_t>(w)]->Signal(SIGKILL);
    workers_[static_cast<std::size_t>(w)]->Wait();
    KillRecord record{phase, "worker-" + std::to_string(w), "", -1, UnixMs()};
    if (!folders.empty()) {
      record.job_id = folders.front().filename().string();
      record.checkpoint_iteration = CheckpointIteration(record.job_id);
    }
    kills_.push_back(record);
    StartWorker(w);
    return true;
  }

  bool PartialOf(const std::vector<std::string>& digests) {
    for (const auto& digest : digests) {
      if (fs::exists(data_ / "partial" / (digest + ".part"))) return true;
    }
    return false;
  }

  bool AllStored(const std::vector<std::string>& digests) {
    for (const auto& digest : digests) {
      if (!fs::exists(data_ / "blobs" / digest.substr(0, 2) / digest)) return false;
    }
    return !digests.empty();
  }

  // Tries once to find `phase` in progress and kill its victim; true when a kill happened.
  bool TryKill(Phase phase, const std::vector<std::set<fs::path>>& folders_before,
               const std::vector<std::map<fs::path, fs::file_time_type>>& checkpoints_before) {
    switch (phase) {
      case Phase::kUpload:
        return KillClient(
            phase, [&](Client& c) { return c.stage == Client::kSubmitting && PartialOf(c.digests); }, 20);
      case Phase::kSubmit:
        return KillClient(
            phase, [&](Client& c) { return c.stage == Client::kSubmitting && AllStored(c.digests); }, 4);
      case Phase::kFetch:
        return KillClient(
            phase, [&](Client& c) { return c.stage == Client::kFetching && fs::exists(c.fetch_dir); }, 30);
      case Phase::kServerWrite: {
        std::error_code error;
        bool busy = !fs::is_empty(data_ / "partial", error) && !error;
        for (std::size_t w = 0; w < work_dirs_.size() && !busy; ++w) {
          for (const auto& folder : JobFolders(work_dirs_[w]))
            busy = busy || fs::exists(folder / "out/report.html");
        }
        if (!busy) return false;
        Pause(10);
        server_->Signal(SIGKILL);
        server_->Wait();
        kills_.push_back({phase, "server", "", -1, UnixMs()});
        StartServer();
        return true;
      }
      default:
        break;
    }
    for (std::size_t w = 0; w < work_dirs_.size(); ++w) {
      for (const auto& folder : JobFolders(work_dirs_[w])) {
        const fs::path checkpoint = folder / "out/model/checkpoint.bin";
        std::error_code error;
        const auto written = fs::last_write_time(checkpoint, error);
        const bool reported = fs::exists(folder / "out/report.html");
        const int worker = static_cast<int>(w);
        switch (phase) {
          case Phase::kLease:
            if (!folders_before[w].count(folder)) return KillWorker(phase, worker, 30);
            break;
          case Phase::kProgress:
            if (fs::exists(folder / "out") && !reported) return KillWorker(phase, worker, 800);
            break;
          case Phase::kCheckpointUpload: {
            const auto before = checkpoints_before[w].find(folder);
            if (!error && !reported && (before == checkpoints_before[w].end() || before->second != written))
              return KillWorker(phase, worker, 15);
            break;
          }
          case Phase::kResultUpload:
            if (reported) return KillWorker(phase, worker, 40);
            break;
          default:
            break;
        }
      }
    }
    return false;
  }

  void KillRound() {
    int done = 0;
    for (std::size_t turn = 0; done < flags_.kills; ++turn) {
      const Phase phase = kPhases[turn % std::size(kPhases)];
      std::vector<std::set<fs::path>> folders_before;
      std::vector<std::map<fs::path, fs::file_time_type>> checkpoints_before;
      for (const auto& work_dir : work_dirs_) {
        auto& folders = folders_before.emplace_back();
        auto& checkpoints = checkpoints_before.emplace_back();
        for (const auto& folder : JobFolders(work_dir)) {
          folders.insert(folder);
          std::error_code error;
          const auto written = fs::last_write_time(folder / "out/model/checkpoint.bin", error);
          if (!error) checkpoints[folder] = written;
        }
      }
      const auto deadline =
          Clock::now() + milliseconds(static_cast<std::int64_t>(flags_.phase_wait_s * 1000));
      bool killed = false;
      while (!killed && Clock::now() < deadline) {
        killed = TryKill(phase, folders_before, checkpoints_before);
        if (!killed) std::this_thread::sleep_for(milliseconds(2));
      }
      if (killed) {
        ++done;
        std::printf("kill %d/%d: %s (%s)\n", done, flags_.kills, Name(phase), kills_.back().victim.c_str());
      } else {
        ++missed_[phase];
        std::printf("phase %s not seen within %.0f s; next phase\n", Name(phase), flags_.phase_wait_s);
      }
      std::fflush(stdout);
    }
  }

  // --- the verdict ----------------------------------------------------------------------------
  struct Attempt {
    std::int64_t unix_ms;
    std::string job_id;
    int resumed_from;  // -1: started from scratch
    bool trained;      // it reached the engine (an attempt killed while it fetched the clip did not)
  };

  // "[2026-12-01 15:20:31.123] ... [cpu0] job ID (attempt K)", the engine's "resumed from
  // .../ID/checkpoint/... at iteration N" and its "clip .../ID/clip: ..." (training starts) that follow
  // it, from every worker log.
  std::vector<Attempt> Attempts() {
    std::vector<Attempt> attempts;
    const std::regex started(
        R"(^\[(\d+)-(\d+)-(\d+) (\d+):(\d+):(\d+)\.(\d+)\].* job ([0-9a-f]{12}) \(attempt \d+\))");
    const std::regex resumed(R"(resumed from .*/([0-9a-f]{12})/checkpoint/\S* at iteration (\d+))");
    const std::regex training(R"(\] clip .*/([0-9a-f]{12})/clip: )");
    for (std::size_t w = 0; w < work_dirs_.size(); ++w) {
      std::ifstream log(dir_ / "logs" / ("worker-" + std::to_string(w) + ".log"));
      std::string line;
      std::smatch match;
      while (std::getline(log, line)) {
        if (std::regex_search(line, match, started)) {
          std::tm tm{};
          tm.tm_year = std::stoi(match[1]) - 1900;
          tm.tm_mon = std::stoi(match[2]) - 1;
          tm.tm_mday = std::stoi(match[3]);
          tm.tm_hour = std::stoi(match[4]);
          tm.tm_min = std::stoi(match[5]);
          tm.tm_sec = std::stoi(match[6]);
          tm.tm_isdst = -1;
          attempts.push_back(
              {static_cast<std::int64_t>(std::mktime(&tm)) * 1000 + std::stoi(match[7]), match[8], -1, false});
        } else if (std::regex_search(line, match, resumed)) {
          for (auto it = attempts.rbegin(); it != attempts.rend(); ++it) {
            if (it->job_id == match[1]) {
              it->resumed_from = std::stoi(match[2]);
              break;
            }
          }
        } else if (std::regex_search(line, match, training)) {
          for (auto it = attempts.rbegin(); it != attempts.rend(); ++it) {
            if (it->job_id == match[1]) {
              it->trained = true;
              break;
            }
          }
        }
      }
    }
    std::sort(attempts.begin(), attempts.end(),
              [](const Attempt& a, const Attempt& b) { return a.unix_ms < b.unix_ms; });
    return attempts;
  }

  int Report(double seconds) {
    std::map<Phase, int> by_phase;
    std::map<std::string, int> by_victim;
    for (const auto& kill : kills_) {
      ++by_phase[kill.phase];
      ++by_victim[kill.victim.substr(0, kill.victim.find('-'))];
    }
    std::printf("kills: %zu in %.0f s (server %d, worker %d, client %d)\n", kills_.size(), seconds,
                by_victim["server"], by_victim["worker"], by_victim["client"]);
    std::printf("  by phase:");
    for (const Phase phase : kPhases)
      std::printf(" %s %d%s", Name(phase), by_phase[phase], phase == Phase::kServerWrite ? "\n" : ",");
    for (const auto& [phase, count] : missed_)
      std::printf("  phase %s not seen %d time(s)\n", Name(phase), count);

    int lost = 0, corrupt = 0, stray = 0;
    std::map<v1::JobState, int> states;
    const auto server_jobs = ListJobs();
    std::map<std::string, int> names;
    if (server_jobs) {
      for (const auto& job : *server_jobs) ++names[job.name()];
    }
    int fetched_files = 0;
    for (const auto& submission : submissions_) {
      ++states[submission.state];
      if (submission.state != submission.intent ||
          (submission.intent == v1::SUCCEEDED && !submission.fetched)) {
        ++lost;
        std::printf("  LOST: %s (job %s) is %s, intended %s%s\n", submission.name.c_str(),
                    submission.job_id.c_str(), v1::JobState_Name(submission.state).c_str(),
                    v1::JobState_Name(submission.intent).c_str(),
                    submission.fetched || submission.intent != v1::SUCCEEDED ? "" : ", results not fetched");
      }
      corrupt += submission.corrupt_files;
      stray += submission.leftover_parts;
      if (submission.fetched) {
        if (const auto job = GetJob(submission.job_id)) fetched_files += job->result().files_size();
      }
      if (names[submission.name] > 1)
        std::printf("  note: %d jobs named %s\n", names[submission.name], submission.name.c_str());
    }
    const int unfinished_submissions = next_submission_ - static_cast<int>(submissions_.size());
    if (unfinished_submissions > 0) {
      lost += unfinished_submissions;
      std::printf("  LOST: %d submission(s) never finished\n", unfinished_submissions);
    }
    std::printf("jobs: %zu submitted: %d SUCCEEDED, %d CANCELLED, %d FAILED, %d other; lost %d\n",
                submissions_.size(), states[v1::SUCCEEDED], states[v1::CANCELLED], states[v1::FAILED],
                static_cast<int>(submissions_.size()) - states[v1::SUCCEEDED] - states[v1::CANCELLED] -
                    states[v1::FAILED],
                lost);
    std::printf("fetched files: %d verified against their SHA-256, %d corrupt\n", fetched_files, corrupt);

    // Resumed runs: after each worker kill that found a checkpoint, the first attempt that reached
    // training (one killed again while it fetched its clip never read the checkpoint).
    const auto attempts = Attempts();
    int resumed = 0, kept = 0;
    double worst = 1.0;
    for (const auto& kill : kills_) {
      if (kill.job_id.empty() || kill.checkpoint_iteration <= 0) continue;
      const auto next = std::find_if(attempts.begin(), attempts.end(), [&](const Attempt& a) {
        return a.job_id == kill.job_id && a.unix_ms > kill.unix_ms && a.trained;
      });
      if (next == attempts.end()) continue;  // the job did not run again (it had completed, or was cancelled)
      ++resumed;
      const double share = std::max(0, next->resumed_from) / static_cast<double>(kill.checkpoint_iteration);
      worst = std::min(worst, share);
      if (share >= 0.9) {
        ++kept;
      } else {
        std::printf("  LOST PROGRESS: job %s resumed at %d, its checkpoint held iteration %d\n",
                    kill.job_id.c_str(), next->resumed_from, kill.checkpoint_iteration);
      }
    }
    lost += resumed - kept;
    std::printf(
        "resumed runs: %d after a kill with a checkpoint; %d kept >= 90%% of its progress (worst %.0f%%)\n",
        resumed, kept, 100 * worst);

    // Stop everything cleanly, then look at what is on disk.
    for (auto& worker : workers_) worker->Signal(SIGTERM);
    for (auto& worker : workers_) worker->Wait();
    server_->Signal(SIGTERM);
    server_->Wait();
    int blobs = 0;
    for (const auto& entry : fs::recursive_directory_iterator(data_)) {
      if (!entry.is_regular_file()) continue;
      const auto relative = fs::relative(entry.path(), data_);
      const std::string top = relative.begin()->string();
      if (top == "blobs") {
        ++blobs;
        if (Sha256File(entry.path()) != entry.path().filename().string()) {
          ++corrupt;
          std::printf("  CORRUPT: blob %s\n", relative.c_str());
        }
      } else if (top == "partial" ? entry.path().extension() != ".part"
                                  // uploads.json.tmp, orphans.json.tmp: a server killed while it wrote the
                                  // file; the next write replaces it.
                                  : !(top.starts_with("jobs.sqlite") || top == "audit.jsonl" ||
                                      top == "server.lock" || top.starts_with("uploads.json") ||
                                      top.starts_with("orphans.json"))) {
        ++stray;
        std::printf("  STRAY: %s\n", relative.c_str());
      }
    }
    for (const auto& work_dir : work_dirs_) {
      for (const auto& folder : JobFolders(work_dir)) {
        ++stray;
        std::printf("  STRAY: %s left in a worker's scratch\n", folder.c_str());
      }
    }
    std::printf("blobs: %d verified against their SHA-256\n", blobs);
    std::printf("files outside the partial area: %d\n", stray);

    const std::string integrity = IntegrityCheck();
    std::printf("job store integrity_check: %s\n", integrity.c_str());
    if (integrity != "ok") ++corrupt;
    const bool all_phases =
        static_cast<int>(by_phase.size()) >= std::min<int>(flags_.kills, std::size(kPhases));
    std::printf("lost=%d corrupt=%d stray=%d kills=%zu phases=%zu/%zu\n", lost, corrupt, stray, kills_.size(),
                by_phase.size(), std::size(kPhases));
    return lost == 0 && corrupt == 0 && stray == 0 && all_phases ? 0 : 1;
  }

  std::string IntegrityCheck() {
    sqlite3* db = nullptr;
    if (sqlite3_open_v2((data_ / "jobs.sqlite").c_str(), &db, SQLITE_OPEN_READONLY, nullptr) != SQLITE_OK) {
      sqlite3_close(db);
      return "cannot open";
    }
    std::string result;
    sqlite3_exec(
        db, "PRAGMA integrity_check",
        [](void* out, int, char** values, char**) {
          auto& text = *static_cast<std::string*>(out);
          text += (text.empty() ? "" : "; ") + std::string(values[0] ? values[0] : "");
          return 0;
        },
        &result, nullptr);
    sqlite3_close(db);
    return result;
  }

  Flags flags_;
  std::mt19937_64 random_;
  fs::path dir_, data_;
  int port_ = 0;
  std::string address_;
  std::unique_ptr<Process> server_;
  std::vector<fs::path> work_dirs_;
  std::vector<std::unique_ptr<Process>> workers_;
  std::unique_ptr<v1::JobService::Stub> stub_;
  std::vector<Client> clients_;
  std::atomic<bool> stop_submitting_{false}, give_up_{false};
  std::atomic<int> next_submission_{0}, active_clients_{0};
  std::mutex results_mutex_;
  std::vector<Submission> submissions_;
  std::vector<KillRecord> kills_;
  std::map<Phase, int> missed_;
};

}  // namespace

int main(int argc, char** argv) {
  Flags flags;
  CLI::App app{
      "fault_campaign: kill -9 at random moments of every phase of the service, count what was lost"};
  app.add_option("--kills", flags.kills, "kills in all (round the eight phases)")->capture_default_str();
  app.add_option("--workers", flags.workers, "endorecon-worker processes (one CPU slot each)")
      ->capture_default_str();
  app.add_option("--clients", flags.clients, "clients submitting, waiting and fetching at once")
      ->capture_default_str();
  app.add_option("--iterations", flags.iterations, "training iterations per job")->capture_default_str();
  app.add_option("--seed", flags.seed, "seed of the kill moments and the clips' padding")
      ->capture_default_str();
  app.add_option("--dir", flags.dir, "scratch folder (default: a new one in $TMPDIR)");
  app.add_option("--phase-wait", flags.phase_wait_s, "seconds to wait for a phase before the next")
      ->capture_default_str();
  app.add_option("--drain", flags.drain_s, "seconds after the last kill for every job to finish")
      ->capture_default_str();
  app.add_option("--pad-mib", flags.pad_mib, "MiB of padding per clip (upload length)")
      ->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  signal(SIGPIPE, SIG_IGN);
  return Campaign(flags).Run();
}
