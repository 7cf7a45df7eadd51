// endorecon delete JOB: a finished job's files (clip, results, checkpoint) are deleted from the
// server now, as retention would delete them later; the job's record stays, marked expired. Deleting
// a job whose files are gone already (deleted before, or by retention) succeeds and says when they went.
#include <CLI/CLI.hpp>
#include <iostream>

#include "client/commands.h"
#include "client/exit_codes.h"
#include "client/job_format.h"
#include "common/grpc_status.h"
#include "common/transport_security.h"

namespace endorecon::client {

Command AddDeleteCommand(CLI::App& app) {
  auto id = std::make_shared<std::string>();
  auto* sub = app.add_subcommand(
      "delete", "delete a finished job's files from the server now (the record stays, marked expired)");
  sub->add_option("JOB", *id, "job id")->required();
  return [id](const Globals& globals) {
    v1::DeleteJobRequest request;
    request.set_id(*id);
    v1::Job job;
    auto context = CallContext(globals.timeout());
    ThrowIfFailed(globals.Connect()->Delete(context.get(), request, &job), "delete " + *id);
    if (globals.json) {
      std::cout << ToJson(job) << std::endl;
    } else {
      std::cout << "job " << job.id() << ": its files were deleted from the server at "
                << HumanTime(job.expired_unix_ms()) << " (its record stays)" << std::endl;
    }
    return kExitOk;
  };
}

}  // namespace endorecon::client
