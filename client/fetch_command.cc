// endorecon fetch JOB -o DIR: download a finished job's results, verified by SHA-256; files
// already there are skipped and an interrupted download resumes.
#include <CLI/CLI.hpp>
#include <filesystem>
#include <iostream>
#include <set>
#include <string>

#include "client/commands.h"
#include "client/exit_codes.h"
#include "client/job_format.h"
#include "common/error.h"
#include "common/file_download.h"
#include "common/grpc_status.h"
#include "common/manifest.h"
#include "common/transport_security.h"

namespace endorecon::client {
namespace {

struct FetchFlags {
  std::string id;
  std::string out;
  double min_bytes_per_second = 1 << 20;
};

// A non-empty folder is taken when everything in it (dot files aside) is one of the results' names
// or a download of one in progress (NAME.part): a fetch again, or one resumed. Anything else is
// someone's files, which results would be mixed into (`fetch -o ~/Documents` was taken; found
// 2026-12-05).
void CheckFetchFolder(const std::filesystem::path& out, const v1::Manifest& result) {
  namespace fs = std::filesystem;
  std::error_code error;
  if (out.empty()) FailInvalid("-o is empty; give a folder");
  if (!fs::exists(out, error)) return;
  if (!fs::is_directory(out, error)) FailInvalid("-o " + out.string() + " is a file; give a folder");
  std::set<std::string> names;
  for (const auto& file : result.files()) {
    const std::string top = fs::path(file.path()).begin()->string();
    names.insert(top);
    names.insert(top + ".part");
  }
  for (fs::directory_iterator it(out, error), end; !error && it != end; it.increment(error)) {
    const std::string name = it->path().filename().string();
    if (name.starts_with(".") || names.contains(name)) continue;
    FailInvalid("-o " + out.string() + " holds other files (" + name +
                ", ...) than this job's results: they would be mixed in; give an empty or new folder");
  }
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
    Fail(ErrorCode::kFailedPrecondition, "job " + job.id() + " is " + v1::JobState_Name(job.state()) +
                                             "; results exist once it has SUCCEEDED");
  }
  CheckFetchFolder(flags.out, job.result());
  const auto pending = PendingDownloads(flags.out, job.result());
  std::int64_t received = 0;
  if (!pending.empty()) {
    v1::FetchRequest request;
    request.set_id(job.id());
    std::int64_t to_receive = 0;
    for (const auto& range : pending) *request.add_files() = range;
    for (const auto& file : job.result().files()) to_receive += file.size();
    auto stream_context = CallContext(
        globals.timeout() + std::chrono::milliseconds(static_cast<std::int64_t>(
                                1000.0 * static_cast<double>(to_receive) / flags.min_bytes_per_second)));
    auto reader = stub->Fetch(stream_context.get(), request);
    received = ReceiveFiles(*reader, flags.out);
    // On disk before "verified" is said: the results may be the only copy once retention runs.
    SyncFolder(flags.out);
  }
  if (globals.json) {
    std::cout << ToJson(job.result()) << std::endl;
  } else {
    std::cout << "fetched " << pending.size() << " of " << job.result().files_size() << " file(s) ("
              << HumanBytes(received) << ") into " << flags.out << "; every file verified" << std::endl;
    for (const auto& file : job.result().files()) {
      if (file.path() == "report.html") {
        std::cout << "report: " << (std::filesystem::path(flags.out) / file.path()).string() << std::endl;
      }
    }
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
