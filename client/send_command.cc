// endorecon send JOB --to PACS: send (again) a SUCCEEDED job's DICOM results to a PACS the server
// knows, and follow the send until it is done or has failed.
#include <CLI/CLI.hpp>
#include <iostream>

#include "client/commands.h"
#include "client/exit_codes.h"
#include "client/job_format.h"
#include "client/job_watcher.h"
#include "common/grpc_status.h"
#include "common/transport_security.h"

namespace endorecon::client {

Command AddSendCommand(CLI::App& app) {
  auto request = std::make_shared<v1::SendRequest>();
  auto wait = std::make_shared<bool>(false);
  auto* sub =
      app.add_subcommand("send", "send a finished job's DICOM results to a PACS configured on the server");
  sub->add_option_function<std::string>(
         "JOB", [request](const std::string& v) { request->set_id(v); }, "job id")
      ->required();
  sub->add_option_function<std::string>(
         "--to", [request](const std::string& v) { request->set_destination(v); },
         "the PACS's name on the server")
      ->required();
  sub->add_flag("--wait", *wait, "follow the send until it is done or failed; exit code 5 when it failed");
  return [request, wait](const Globals& globals) {
    v1::Job job;
    auto context = CallContext(globals.timeout());
    ThrowIfFailed(globals.Connect()->Send(context.get(), *request, &job), "send " + request->id());
    if (*wait) job = WatchJob(globals, request->id(), {});
    std::cout << (globals.json ? ToJson(job) + "\n" : DicomLines(job));
    for (const auto& send : job.sends()) {
      if (send.destination() == request->destination() && send.state() == v1::DicomSend::SEND_FAILED) {
        return kExitJobFailed;
      }
    }
    return kExitOk;
  };
}

}  // namespace endorecon::client
