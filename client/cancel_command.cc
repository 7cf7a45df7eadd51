// endorecon cancel JOB: a queued job is cancelled at once, a running one within seconds.
#include <CLI/CLI.hpp>
#include <iostream>

#include "client/commands.h"
#include "client/exit_codes.h"
#include "client/job_format.h"
#include "common/grpc_status.h"
#include "common/transport_security.h"

namespace endorecon::client {

Command AddCancelCommand(CLI::App& app) {
  auto id = std::make_shared<std::string>();
  auto* sub = app.add_subcommand("cancel", "cancel a queued or running job");
  sub->add_option("JOB", *id, "job id")->required();
  return [id](const Globals& globals) {
    v1::CancelJobRequest request;
    request.set_id(*id);
    v1::Job job;
    auto context = CallContext(globals.timeout());
    ThrowIfFailed(globals.Connect()->Cancel(context.get(), request, &job), "cancel " + *id);
    if (globals.json) {
      std::cout << ToJson(job) << std::endl;
    } else if (job.state() == v1::CANCELLED) {
      std::cout << "job " << job.id() << " cancelled" << std::endl;
    } else {
      std::cout << "job " << job.id() << " cancel requested; its worker stops within seconds" << std::endl;
    }
    return kExitOk;
  };
}

}  // namespace endorecon::client
