// endorecon drain WORKER [--undo]: an admin takes a worker out of service for maintenance. The
// server gives it no new job; the jobs it runs go on, and once `endorecon workers` shows it holds
// none it can be stopped. --undo (or the worker's restart) ends the drain.
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <iostream>

#include "client/commands.h"
#include "client/exit_codes.h"
#include "client/job_format.h"
#include "common/grpc_status.h"
#include "common/transport_security.h"

namespace endorecon::client {

Command AddDrainCommand(CLI::App& app) {
  auto request = std::make_shared<v1::DrainRequest>();
  auto* sub = app.add_subcommand(
      "drain", "give a worker no new job (maintenance); its running jobs go on (admin only)");
  sub->add_option("WORKER", *request->mutable_worker_id(), "worker id, as `endorecon workers` lists it")
      ->required();
  sub->add_flag(
      "--undo", [request](std::int64_t) { request->set_undo(true); }, "end the drain: the worker serves again");
  return [request](const Globals& globals) {
    v1::WorkerInfo worker;
    auto context = CallContext(globals.timeout());
    ThrowIfFailed(globals.Connect()->Drain(context.get(), *request, &worker), "drain " + request->worker_id());
    if (globals.json) {
      std::cout << ToJson(worker) << std::endl;
    } else if (request->undo()) {
      std::cout << "worker " << worker.id() << " serves again: it is given jobs" << std::endl;
    } else if (worker.job_ids_size() == 0) {
      std::cout << "worker " << worker.id() << " drains: it is given no new job and runs none; it can be stopped"
                << std::endl;
    } else {
      std::cout << fmt::format(
                       "worker {} drains: it is given no new job; its job(s) {} go on (stop it once `endorecon "
                       "workers` shows none)",
                       worker.id(), fmt::join(worker.job_ids(), ","))
                << std::endl;
    }
    return kExitOk;
  };
}

}  // namespace endorecon::client
