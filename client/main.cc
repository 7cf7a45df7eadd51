// endorecon: the thin client of endorecon-server (no engine linked). Uploads clips, submits,
// watches, lists, cancels and fetches reconstruction jobs.
#include <fmt/format.h>
#include <grpc/support/log.h>
#include <spdlog/sinks/stdout_sinks.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <map>
#include <string>
#include <string_view>

#include "client/commands.h"
#include "client/exit_codes.h"
#include "common/cli_checks.h"
#include "common/cli_usage.h"
#include "common/error.h"
#include "common/filesystem_failure.h"
#include "common/job_bounds.h"
#include "common/transport_security.h"
#include "endorecon_version.h"

namespace endorecon::client {

std::shared_ptr<grpc::Channel> Globals::Channel() const {
  ChannelSecurity security;
  security.ca_file = ca_file;
  security.insecure = insecure;
  if (!token_file.empty()) {
    security.token = ReadTokenFile(token_file, "--token-file");
  } else if (const char* token = std::getenv("ENDORECON_TOKEN"); token && *token) {
    security.token = CleanToken(token, "$ENDORECON_TOKEN");
  }
  return OpenChannel(server, security);
}

std::unique_ptr<v1::JobService::Stub> Globals::Connect() const { return v1::JobService::NewStub(Channel()); }

namespace {

// What the user can do about a refusal the server's answer alone does not explain.
std::string HintFor(const endorecon::Error& error, const Globals& globals) {
  // Nothing listens there: TLS has nothing to do with it.
  const bool refused = std::string_view(error.what()).find("Connection refused") != std::string_view::npos;
  if (error.code() == endorecon::ErrorCode::kUnavailable && refused)
    return "\nendorecon: nothing listens at " + globals.server +
           ": is the server running, and is --server (or ENDORECON_SERVER) its --listen address?";
  // An HTTP port (the metrics') answers, but not in HTTP/2: TLS has nothing to do with it either.
  if (error.code() == endorecon::ErrorCode::kUnavailable &&
      std::string_view(error.what()).find("Failed parsing HTTP/2") != std::string_view::npos)
    return "\nendorecon: " + globals.server +
           " answers, but not as endorecon-server's job API: is it the metrics or health port?";
  // Connected, and no answer within the deadline: a server too busy, stopped (SIGSTOP), or another
  // service that takes connections and says nothing. It said only "Deadline Exceeded" (found 2026-12-07).
  if (error.code() == endorecon::ErrorCode::kUnavailable &&
      std::string_view(error.what()).find("Deadline Exceeded") != std::string_view::npos)
    return "\nendorecon: " + globals.server + " took the connection but did not answer within --timeout (" +
           fmt::format("{:g}", globals.timeout_s) +
           " s): is the server overloaded or stopped, or is the address another service's?";
  if (error.code() == endorecon::ErrorCode::kUnavailable) {
    endorecon::ChannelSecurity security;
    security.ca_file = globals.ca_file;
    if (auto hint = endorecon::TlsFailureHint(error.what(), security); !hint.empty())
      return "\nendorecon: " + hint;
  }
  // A plaintext channel to a TLS port fails to connect; a call cut mid-way (a server restart) or a
  // local file that cannot be written has nothing to do with TLS (the hint followed every UNAVAILABLE).
  if (error.code() == endorecon::ErrorCode::kUnavailable && globals.ca_file.empty() &&
      std::string_view(error.what()).find("failed to connect to all addresses") != std::string_view::npos)
    return "\nendorecon: if the server uses TLS, pass --ca FILE or set ENDORECON_CA";
  if (error.code() == endorecon::ErrorCode::kUnauthenticated && globals.token_file.empty() &&
      !std::getenv("ENDORECON_TOKEN"))
    return "\nendorecon: pass --token-file FILE or set ENDORECON_TOKEN";
  return "";
}

// `rc`, unless what the command wrote to stdout did not all arrive: `list --json > jobs.json` on a full
// disk exited 0 with the file cut short (found 2026-12-06). 8 for a full disk, as a server's; else 1.
int OutputWritten(int rc) {
  errno = 0;
  const bool flushed = std::fflush(stdout) == 0;
  int error = errno;
  if (flushed && !std::ferror(stdout) && std::cout.good()) return rc;
  // The write that failed was an earlier flush (std::endl), whose errno is gone: a byte more asks again.
  if (error == 0 && ::write(STDOUT_FILENO, "\n", 1) < 0) error = errno;
  std::cerr << "endorecon: cannot write the output to stdout"
            << (error != 0 ? std::string(" (") + std::strerror(error) + ")" : std::string())
            << ": what was written is incomplete\n";
  return error == ENOSPC || error == EDQUOT ? kExitResourceExhausted : kExitInternal;
}

}  // namespace

}  // namespace endorecon::client

int main(int argc, char** argv) {
  using namespace endorecon::client;
  // What the shared code logs (a token about to expire) goes to stderr, as every message of the CLI:
  // stdout carries results, JSON with --json.
  spdlog::set_default_logger(spdlog::stderr_logger_mt("endorecon"));
  // gRPC's own log lines ("E1205 21:49:14 ssl_transport_security.cc:1501] Handshake failed ...") went
  // to the user's terminal beside the CLI's message, which says the same with a hint: kept out unless
  // asked for with GRPC_VERBOSITY.
  if (std::getenv("GRPC_VERBOSITY") == nullptr) gpr_set_log_function([](gpr_log_func_args*) {});
  spdlog::set_pattern("endorecon: %l: %v");
  CLI::App app{
      "endorecon: submit endoscopic clips to endorecon-server, watch the reconstruction, fetch results"};
  app.footer(std::string(kExitCodeHelp) +
             " Global options (endorecon --help) may also follow the subcommand.");
  app.require_subcommand(1);
  // Global options are accepted after the subcommand too (`endorecon submit clip --json`, as git, docker
  // and kubectl users type them): every subcommand, added below, inherits this and hands the options it
  // does not know to the app, so any global option added later works there without more code.
  app.fallthrough();
  Globals globals;
  const char* env_server = std::getenv("ENDORECON_SERVER");
  globals.server = env_server && *env_server ? env_server : "127.0.0.1:50051";
  app.add_option("--server", globals.server,
                 "server address host:port (default: $ENDORECON_SERVER or 127.0.0.1:50051)")
      ->check(endorecon::ServerAddress());
  app.add_flag("--json", globals.json, "machine-readable JSON on stdout (JSON Lines for streams)");
  app.add_option("--timeout", globals.timeout_s, "deadline of each call in seconds")
      ->capture_default_str()
      ->check(endorecon::AboveZero());
  const char* env_ca = std::getenv("ENDORECON_CA");
  globals.ca_file = env_ca ? env_ca : "";
  app.add_option("--ca", globals.ca_file,
                 "TLS: verify the server against this CA certificate (default: $ENDORECON_CA)");
  app.add_option("--token-file", globals.token_file,
                 "file holding the bearer token (mode 0600; default: the token in $ENDORECON_TOKEN)");
  app.add_flag("--insecure", globals.insecure,
               "send the token without TLS to an address beyond loopback (isolated test networks only)");
  std::map<std::string, Command> commands;
  commands["submit"] = AddSubmitCommand(app);
  commands["status"] = AddStatusCommand(app);
  commands["watch"] = AddWatchCommand(app);
  commands["list"] = AddListCommand(app);
  commands["cancel"] = AddCancelCommand(app);
  commands["delete"] = AddDeleteCommand(app);
  commands["fetch"] = AddFetchCommand(app);
  commands["workers"] = AddWorkersCommand(app);
  commands["drain"] = AddDrainCommand(app);
  commands["send"] = AddSendCommand(app);
  commands["uploads"] = AddUploadsCommand(app);
  app.set_version_flag("--version", ENDORECON_VERSION);
  endorecon::DecimalIntegers(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e) == 0 ? kExitOk : kExitInvalid;  // --help, --version
    // A mistyped command or option is named, with the nearest known one. CLI11 repeats the words it
    // did not expect: a token typed after a "--token" that does not exist went to the terminal and
    // its scrollback whole (found 2026-12-06).
    const std::string mistake = endorecon::UsageMistake(app, argc, argv);
    std::cerr << (mistake.empty() ? std::string() : "endorecon: ")
              << endorecon::PrintableLines(mistake.empty() ? endorecon::WithoutTokens(e.what()) : mistake)
              << "\n";
    for (int i = 1; i < argc; ++i) {
      if (std::string_view(argv[i]).rfind("--token", 0) == 0 && std::string_view(argv[i]) != "--token-file") {
        std::cerr
            << "endorecon: a token is given by --token-file FILE (mode 0600) or $ENDORECON_TOKEN, never "
               "on the command line, where other users' `ps` shows it\n";
        break;
      }
    }
    if (mistake.empty()) std::cerr << "Run with --help for more information.\n";
    return kExitInvalid;
  }
  if (app.count("--server") == 0) {  // $ENDORECON_SERVER, checked as --server is
    std::string server = globals.server;
    if (const std::string problem = endorecon::ServerAddress()(server); !problem.empty()) {
      std::cerr << "endorecon: ENDORECON_SERVER: " << problem << "\n";
      return kExitInvalid;
    }
  }
  try {
    for (auto* sub : app.get_subcommands()) return OutputWritten(commands.at(sub->get_name())(globals));
  } catch (const endorecon::Error& e) {
    // A token pasted where a job id or a file name goes is repeated in messages: its secret is not.
    std::cerr << "endorecon: " << endorecon::ErrorCodeName(e.code()) << ": "
              << endorecon::PrintableLines(endorecon::WithoutTokens(e.what())) << HintFor(e, globals) << "\n";
    return ExitCodeFor(e.code());
  } catch (const std::filesystem::filesystem_error& e) {
    // A local file or folder the system refused (a clip this user may not read): the path and why, as
    // input to correct. It said "filesystem error: status: Permission denied [PATH]", exit 1 (found
    // 2026-12-07).
    std::cerr << "endorecon: " << endorecon::PrintableLines(endorecon::DescribeFilesystemError(e)) << "\n";
    return endorecon::IsUsersFileProblem(e.code().value()) ? kExitInvalid : kExitInternal;
  } catch (const std::exception& e) {
    std::cerr << "endorecon: " << endorecon::PrintableLines(endorecon::WithoutTokens(e.what())) << "\n";
    return kExitInternal;
  }
  return kExitOk;
}
