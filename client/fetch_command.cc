// endorecon fetch JOB -o DIR: download a finished job's results, verified by SHA-256; files
// already there are skipped and an interrupted download resumes.
#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <cctype>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "client/commands.h"
#include "client/exit_codes.h"
#include "client/interrupt_note.h"
#include "client/job_format.h"
#include "common/error.h"
#include "common/file_download.h"
#include "common/grpc_status.h"
#include "common/job_bounds.h"
#include "common/job_results_text.h"
#include "common/manifest.h"
#include "common/transport_security.h"

namespace endorecon::client {
namespace {

struct FetchFlags {
  std::string id;
  std::string out;
  double min_bytes_per_second = 1 << 20;
};

// An open file, closed (and so unlocked) with its owner.
class FileDescriptor {
 public:
  explicit FileDescriptor(int fd) : fd_(fd) {}
  FileDescriptor(FileDescriptor&& other) noexcept : fd_(std::exchange(other.fd_, -1)) {}
  FileDescriptor(const FileDescriptor&) = delete;
  FileDescriptor& operator=(const FileDescriptor&) = delete;
  ~FileDescriptor() {
    if (fd_ >= 0) ::close(fd_);
  }
  int get() const { return fd_; }

 private:
  int fd_;
};

// The file in a fetch's folder that names the job whose results it holds. Held locked while a fetch
// writes there: four fetches into one folder mixed their partial files and failed as checksum
// mismatches, and a folder holding another job's results took this one's over them (found
// 2026-12-05).
constexpr const char* kJobMark = ".endorecon-job";

// A non-empty folder is taken when everything in it (dot files at its top aside) is one of the
// results' files or a download of one in progress (PATH.part): a fetch again, or one resumed.
// Anything else is someone's files, or another job's results, which these would be mixed into
// (`fetch -o ~/Documents` was taken; found 2026-12-05).
void CheckFetchFolder(const std::filesystem::path& out, const v1::Manifest& result) {
  namespace fs = std::filesystem;
  std::error_code error;
  if (out.empty()) FailInvalid("-o is empty; give a folder");
  if (!fs::exists(out, error)) return;
  if (!fs::is_directory(out, error)) FailInvalid("-o " + out.string() + " is a file; give a folder");
  std::set<std::string> names;
  for (const auto& file : result.files()) {
    names.insert(file.path());
    names.insert(file.path() + ".part");
  }
  std::vector<std::string> others;  // ", ..." followed the one named even when it was alone (2026-12-07)
  for (fs::recursive_directory_iterator it(out, error), end; !error && it != end; it.increment(error)) {
    const std::string name = it->path().lexically_relative(out).generic_string();
    if (it.depth() == 0 && it->path().filename().string().starts_with(".")) {
      if (it->is_directory(error)) it.disable_recursion_pending();
      continue;
    }
    if (it->is_directory(error) || names.contains(name)) continue;
    others.push_back(name);
    if (others.size() > 1) break;  // one named, and whether there are more
  }
  if (!others.empty()) {
    FailInvalid("-o " + out.string() + " holds other files (" + others.front() +
                (others.size() > 1 ? ", ..." : "") +
                ") than this job's results: they would be mixed in; give an empty or new folder");
  }
}

// Opens and locks `out`/.endorecon-job for job `id`, refusing a folder another fetch is writing into
// or one that holds another job's results. The lock lasts as long as the returned descriptor.
FileDescriptor MarkFetchFolder(const std::filesystem::path& out, const std::string& id) {
  std::error_code error;
  std::filesystem::create_directories(out, error);
  if (error) FailInvalid("-o " + out.string() + ": cannot make the folder: " + error.message());
  const auto mark = out / kJobMark;
  FileDescriptor fd(::open(mark.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644));
  if (fd.get() < 0) {
    Fail(ErrorCode::kInternal, "cannot open " + mark.string() + ": " + std::strerror(errno));
  }
  if (::flock(fd.get(), LOCK_EX | LOCK_NB) != 0) {
    Fail(ErrorCode::kFailedPrecondition,
         "another endorecon fetch is writing into " + out.string() + ": wait for it, or give another folder");
  }
  char held[64] = {};
  const ssize_t n = ::pread(fd.get(), held, sizeof(held) - 1, 0);
  std::string before(held, n > 0 ? static_cast<std::size_t>(n) : 0);
  while (!before.empty() && std::isspace(static_cast<unsigned char>(before.back()))) before.pop_back();
  if (!before.empty() && before != id) {
    FailInvalid("-o " + out.string() + " holds the results of job " + before + " (" + mark.string() +
                "), not of job " + id + ": give an empty or new folder");
  }
  const std::string text = id + "\n";
  if (::ftruncate(fd.get(), 0) != 0 ||
      ::pwrite(fd.get(), text.data(), text.size(), 0) != static_cast<ssize_t>(text.size())) {
    Fail(ErrorCode::kInternal, "cannot write " + mark.string() + ": " + std::strerror(errno));
  }
  return fd;
}

int Fetch(const Globals& globals, const FetchFlags& flags) {
  const auto stub = globals.Connect();
  v1::GetJobRequest get;
  get.set_id(flags.id);
  v1::Job job;
  auto context = CallContext(globals.timeout());
  ThrowIfFailed(stub->Get(context.get(), get, &job), "fetch " + flags.id);
  if (job.expired_unix_ms() > 0) {
    Fail(ErrorCode::kFailedPrecondition,
         "job " + job.id() + " expired on " + HumanTime(job.expired_unix_ms()) +
             ": its clip and results were deleted from the server (retention, or `endorecon delete`)");
  }
  if (job.state() != v1::SUCCEEDED) {
    Fail(ErrorCode::kFailedPrecondition, NoResultsYet(job, "fetched"));
  }
  CheckFetchFolder(flags.out, job.result());
  // Results hold patient data (DICOM names the patient): what fetch creates is the user's alone, as
  // everything the server keeps is. They followed the umask, 0644 (found 2026-12-06).
  ::umask(077);
  const FileDescriptor mark = MarkFetchFolder(flags.out, job.id());
  const auto pending = PendingDownloads(flags.out, job.result());
  std::int64_t received = 0;
  // Stopped by Ctrl-C or SIGTERM, it said nothing (found 2026-12-06).
  const InterruptNote interrupt_note(
      "fetch interrupted; the files fetched so far are kept: run the same `endorecon fetch " + job.id() +
      " -o " + PrintableText(flags.out, 200) +
      "` again to finish (every file is checked against its digest)");
  if (!pending.empty()) {
    v1::FetchRequest request;
    request.set_id(job.id());
    std::int64_t to_receive = 0;
    for (const auto& range : OnePerContent(pending)) *request.add_files() = range;
    for (const auto& file : job.result().files()) to_receive += file.size();
    auto stream_context = CallContext(
        globals.timeout() + std::chrono::milliseconds(static_cast<std::int64_t>(
                                1000.0 * static_cast<double>(to_receive) / flags.min_bytes_per_second)));
    auto reader = stub->Fetch(stream_context.get(), request);
    try {
      received = ReceiveFiles(*reader, flags.out);
    } catch (const Error& e) {
      // A server that went away mid-download (a restart, a crash) said only "recvmsg: Connection
      // reset by peer" (found 2026-12-07): the fetch resumes, so say how.
      if (e.code() != ErrorCode::kUnavailable) throw;
      Fail(e.code(), std::string(e.what()) +
                         "; the files fetched so far are kept: run the same `endorecon fetch " + job.id() +
                         " -o " + PrintableText(flags.out, 200) + "` again to resume");
    }
    CopyDuplicates(flags.out, pending);
    // On disk before "verified" is said: the results may be the only copy once retention runs.
    SyncFolder(flags.out);
  }
  std::string report;
  for (const auto& file : job.result().files()) {
    if (file.path() == "report.html") report = (std::filesystem::path(flags.out) / file.path()).string();
  }
  if (globals.json) {
    // What the text says, for scripts: where the results went, what was fetched now, the manifest (it
    // printed the manifest alone).
    nlohmann::json out = {{"job", job.id()},
                          {"out", flags.out},
                          {"report", report.empty() ? nlohmann::json(nullptr) : nlohmann::json(report)},
                          {"fetched_files", pending.size()},
                          {"files", job.result().files_size()},
                          {"received_bytes", received},
                          {"result", nlohmann::json::parse(ToJson(job.result()))}};
    std::cout << out.dump() << std::endl;
  } else {
    if (pending.empty()) {
      std::cout << "all " << job.result().files_size() << " file(s) are in " << flags.out
                << " already; every file verified" << std::endl;
    } else {
      // The pending files' bytes, as `status` counts them: identical files come once and are copied
      // here, so the bytes received can be fewer ("115.0 MB" in status read as 103.6 fetched; found
      // 2026-12-07).
      std::map<std::string, std::int64_t> sizes;
      for (const auto& file : job.result().files()) sizes[file.path()] = file.size();
      std::int64_t fetched = 0;
      for (const auto& range : pending) fetched += sizes[range.path()] - range.offset();
      std::cout << "fetched " << pending.size() << " of " << job.result().files_size() << " file(s) ("
                << HumanBytes(fetched)
                << (received < fetched
                        ? ", " + HumanBytes(received) + " of it received: identical files come once"
                        : std::string())
                << ") into " << flags.out << "; every file verified" << std::endl;
    }
    if (!report.empty()) std::cout << "report: " << report << std::endl;
  }
  return kExitOk;
}

}  // namespace

Command AddFetchCommand(CLI::App& app) {
  auto flags = std::make_shared<FetchFlags>();
  auto* sub = app.add_subcommand("fetch", "download a finished job's results (verified, resumable)");
  sub->add_option("JOB", flags->id, "job id")->required();
  sub->add_option("-o,--output", flags->out, "folder to write the results into")->required();
  return [flags](const Globals& globals) { return Fetch(globals, *flags); };
}

}  // namespace endorecon::client
