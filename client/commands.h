// Each `endorecon` subcommand registers itself on the CLI11 app and returns the callback that runs
// it (returning the process exit code, see exit_codes.h). One file per subcommand.
#pragma once

#include <chrono>
#include <functional>
#include <memory>
#include <string>

#include "endorecon/v1/job_service.grpc.pb.h"

namespace CLI {
class App;
}

namespace endorecon::client {

// Flags shared by every subcommand.
struct Globals {
  std::string server;      // --server, else $ENDORECON_SERVER, else 127.0.0.1:50051
  bool json = false;       // --json: machine-readable output on stdout
  double timeout_s = 30;   // --timeout: deadline of each unary call
  std::string ca_file;     // --ca, else $ENDORECON_CA: TLS, verifying the server against this CA
  std::string token_file;  // --token-file: the bearer token; else $ENDORECON_TOKEN holds the token itself
  bool insecure = false;   // --insecure: the token without TLS beyond loopback (isolated test networks)
  std::chrono::milliseconds timeout() const {
    return std::chrono::milliseconds(static_cast<long>(timeout_s * 1000));
  }
  // A channel with the TLS and token settings above. Throws Error(kInvalidArgument) for an
  // unreadable or world-readable token file.
  std::shared_ptr<grpc::Channel> Channel() const;
  // A stub over Channel().
  std::unique_ptr<v1::JobService::Stub> Connect() const;
};

using Command = std::function<int(const Globals&)>;

Command AddSubmitCommand(CLI::App& app);
Command AddStatusCommand(CLI::App& app);
Command AddWatchCommand(CLI::App& app);
Command AddListCommand(CLI::App& app);
Command AddCancelCommand(CLI::App& app);
Command AddDeleteCommand(CLI::App& app);
Command AddFetchCommand(CLI::App& app);
Command AddWorkersCommand(CLI::App& app);
Command AddDrainCommand(CLI::App& app);
Command AddSendCommand(CLI::App& app);
Command AddUploadsCommand(CLI::App& app);

}  // namespace endorecon::client
