// endorecon workers: the workers the server has heard from.
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <iostream>

#include "client/commands.h"
#include "client/exit_codes.h"
#include "client/job_format.h"
#include "common/grpc_status.h"
#include "common/transport_security.h"

namespace endorecon::client {

Command AddWorkersCommand(CLI::App& app) {
  app.add_subcommand("workers",
                     "list the workers: alive or not, devices (kind, model, memory, threads), jobs, version");
  return [](const Globals& globals) {
    v1::ListWorkersResponse response;
    auto context = CallContext(globals.timeout());
    ThrowIfFailed(globals.Connect()->ListWorkers(context.get(), {}, &response), "workers");
    if (globals.json) {
      std::cout << ToJson(response) << std::endl;
      return kExitOk;
    }
    std::cout << fmt::format("{:<28} {:<8} {:<16} {:<19} {}\n", "WORKER", "ALIVE", "DEVICES", "LAST SEEN",
                             "JOBS");
    for (const auto& worker : response.workers()) {
      // A draining worker (endorecon drain) is given no new job.
      const char* alive = worker.draining() ? (worker.alive() ? "draining" : "no")
                          : worker.alive()  ? "yes"
                                            : "no";
      std::cout << fmt::format("{:<28} {:<8} {:<16} {:<19} {}\n", worker.id(), alive,
                               fmt::format("{}", fmt::join(worker.devices(), ",")),
                               HumanTime(worker.last_seen_unix_ms()),
                               fmt::format("{}", fmt::join(worker.job_ids(), ",")));
      if (!worker.version().empty()) std::cout << fmt::format("  version {}\n", worker.version());
      if (!worker.tenant().empty())
        std::cout << fmt::format("  runs the jobs of tenant '{}' only (its token's)\n", worker.tenant());
      for (const auto& device : worker.device_info()) {
        std::cout << fmt::format("  {}: {}, {}, {}, {} host thread(s)\n", device.name(), device.kind(),
                                 device.model(), HumanBytes(device.memory_bytes()), device.threads());
      }
    }
    return kExitOk;
  };
}

}  // namespace endorecon::client
