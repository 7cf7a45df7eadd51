// endorecon list: jobs, newest first, one line each.
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cctype>
#include <iostream>

#include "client/commands.h"
#include "client/exit_codes.h"
#include "client/job_format.h"
#include "common/cli_checks.h"
#include "common/error.h"
#include "common/grpc_status.h"
#include "common/transport_security.h"

namespace endorecon::client {
namespace {

// What the name is followed by: files deleted, and DICOM sends that failed (a SUCCEEDED job whose
// results did not reach a PACS showed as any other; found 2026-12-05).
std::string Marks(const v1::Job& job) {
  std::string marks = job.expired_unix_ms() > 0 ? " [files deleted]" : "";
  for (const auto& send : job.sends()) {
    if (send.state() == v1::DicomSend::SEND_FAILED) marks += " [send to " + send.destination() + " failed]";
  }
  return marks;
}

struct ListFlags {
  std::vector<std::string> states;
  int limit = 50;
  std::string page_token;  // a listing's next_page_token: go on from there (its JSON gave it, unusable)
};

int List(const Globals& globals, const ListFlags& flags) {
  v1::ListJobsRequest request;
  for (const auto& name : flags.states) {
    v1::JobState state;
    std::string upper = name;  // `--state queued` as `--state QUEUED`
    for (char& c : upper) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
    if (!v1::JobState_Parse(upper, &state))
      FailInvalid("--state " + name + ": expected QUEUED, RUNNING, SUCCEEDED, FAILED or CANCELLED");
    request.add_states(state);
  }
  const auto stub = globals.Connect();
  request.set_page_token(flags.page_token);
  v1::ListJobsResponse all;
  do {
    request.set_page_size(std::min(flags.limit - all.jobs_size(), 1000));
    v1::ListJobsResponse page;
    auto context = CallContext(globals.timeout());
    ThrowIfFailed(stub->List(context.get(), request, &page), "list");
    for (const auto& job : page.jobs()) *all.add_jobs() = job;
    request.set_page_token(page.next_page_token());
  } while (!request.page_token().empty() && all.jobs_size() < flags.limit);
  // Jobs beyond --limit are said to exist: a script counting jobs got 50 without a word (found
  // 2026-12-05). JSON carries the server's next_page_token, empty when none are left.
  all.set_next_page_token(request.page_token());
  if (!request.page_token().empty()) {
    std::cerr << "endorecon: " << all.jobs_size()
              << " job(s) are listed and there are more: --limit N lists more, "
              << "--page-token " << request.page_token() << " goes on from here" << std::endl;
  }
  if (globals.json) {
    std::cout << ToJson(all) << std::endl;
    return kExitOk;
  }
  // Jobs of tenants (a server with tokens) get the tenant column; an admin sees several.
  const bool tenants = std::any_of(all.jobs().begin(), all.jobs().end(),
                                   [](const v1::Job& job) { return !job.tenant().empty(); });
  const auto tenant_of = [&](const v1::Job& job) {
    return tenants ? fmt::format("{:<16} ", job.tenant().empty() ? "-" : job.tenant()) : std::string();
  };
  std::cout << fmt::format("{:<14} {}{:<10} {:>4} {:<19} {:>12} {}\n", "JOB",
                           tenants ? "TENANT           " : "", "STATE", "PRIO", "CREATED", "ITERATION",
                           "NAME");
  for (const auto& job : all.jobs()) {
    // Training's iterations; frames, said so, while the results are evaluated or a recording is
    // prepared (a finished job showed "12/12" for its evaluation's frames as if iterations).
    // A finished job shows the iterations it trained (its summary), not its evaluation's last frame.
    const auto& p = job.progress();
    const std::string phase = p.phase() == "evaluate" ? "eval " : p.phase() == "prepare" ? "prep " : "";
    const auto trained = TrainedIterations(job);
    const std::string iteration = trained                      ? std::to_string(*trained)
                                  : p.phase() == "upload"      ? std::string("upload")
                                  : p.phase() == "upload-wait" ? std::string("upload-wait")
                                  : job.has_progress()
                                      ? fmt::format("{}{}/{}", phase, p.iteration(), p.total_iterations())
                                      : "-";
    std::cout << fmt::format("{:<14} {}{:<10} {:>4} {:<19} {:>12} {}\n", job.id(), tenant_of(job),
                             v1::JobState_Name(job.state()), job.priority(), HumanTime(job.created_unix_ms()),
                             iteration, job.name() + Marks(job));
  }
  return kExitOk;
}

}  // namespace

Command AddListCommand(CLI::App& app) {
  auto flags = std::make_shared<ListFlags>();
  auto* sub = app.add_subcommand("list", "list jobs, newest first");
  sub->add_option("--state", flags->states, "only jobs in these states (repeatable)");
  sub->add_option("--limit", flags->limit, "at most this many jobs")
      ->capture_default_str()
      ->check(AboveZero());
  sub->add_option("--page-token", flags->page_token,
                  "go on from where a listing with the same --state left off (its next_page_token)");
  return [flags](const Globals& globals) { return List(globals, *flags); };
}

}  // namespace endorecon::client
