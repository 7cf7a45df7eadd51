// endorecon: the thin client of endorecon-server (no engine linked). Uploads clips, submits,
// watches, lists, cancels and fetches reconstruction jobs.
#include <CLI/CLI.hpp>
#include <cstdlib>
#include <iostream>
#include <map>
#include <string>

#include "client/commands.h"
#include "client/exit_codes.h"
#include "common/error.h"
#include "common/transport_security.h"

namespace endorecon::client {

std::unique_ptr<v1::JobService::Stub> Globals::Connect() const {
  return v1::JobService::NewStub(OpenChannel(server));
}

}  // namespace endorecon::client

int main(int argc, char** argv) {
  using namespace endorecon::client;
  CLI::App app{
      "endorecon: submit endoscopic clips to endorecon-server, watch the reconstruction, fetch results"};
  app.footer(kExitCodeHelp);
  app.require_subcommand(1);
  Globals globals;
  const char* env_server = std::getenv("ENDORECON_SERVER");
  globals.server = env_server && *env_server ? env_server : "127.0.0.1:50051";
  app.add_option("--server", globals.server,
                 "server address host:port (default: $ENDORECON_SERVER or 127.0.0.1:50051)");
  app.add_flag("--json", globals.json, "machine-readable JSON on stdout (JSON Lines for streams)");
  app.add_option("--timeout", globals.timeout_s, "deadline of each call in seconds")->capture_default_str();
  std::map<std::string, Command> commands;
  commands["submit"] = AddSubmitCommand(app);
  commands["status"] = AddStatusCommand(app);
  commands["watch"] = AddWatchCommand(app);
  commands["list"] = AddListCommand(app);
  commands["cancel"] = AddCancelCommand(app);
  commands["fetch"] = AddFetchCommand(app);
  commands["workers"] = AddWorkersCommand(app);
  commands["send"] = AddSendCommand(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? kExitOk : kExitInvalid;
  }
  try {
    for (auto* sub : app.get_subcommands()) return commands.at(sub->get_name())(globals);
  } catch (const endorecon::Error& e) {
    std::cerr << "endorecon: " << endorecon::ErrorCodeName(e.code()) << ": " << e.what() << "\n";
    return ExitCodeFor(e.code());
  } catch (const std::exception& e) {
    std::cerr << "endorecon: " << e.what() << "\n";
    return kExitInternal;
  }
  return kExitOk;
}
