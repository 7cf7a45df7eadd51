// endorecon status JOB: one job in detail.
#include <CLI/CLI.hpp>
#include <iostream>

#include "client/commands.h"
#include "client/exit_codes.h"
#include "client/job_format.h"
#include "common/grpc_status.h"
#include "common/transport_security.h"

namespace endorecon::client {

Command AddStatusCommand(CLI::App& app) {
  auto id = std::make_shared<std::string>();
  auto* sub = app.add_subcommand("status", "show one job: state, progress, attempts, reason, results");
  sub->add_option("JOB", *id, "job id")->required();
  return [id](const Globals& globals) {
    v1::GetJobRequest request;
    request.set_id(*id);
    v1::Job job;
    auto context = CallContext(globals.timeout());
    ThrowIfFailed(globals.Connect()->Get(context.get(), request, &job), "status " + *id);
    std::cout << (globals.json ? ToJson(job) + "\n" : DescribeJob(job));
    return kExitOk;
  };
}

}  // namespace endorecon::client
