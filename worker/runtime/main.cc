// endorecon-worker: the engine's command line (synth, reconstruct, render, prepare, calibrate) and the
// service worker (serve), which leases jobs from endorecon-server and runs one engine per device.
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <filesystem>
#include <map>
#include <string>

#include "common/cli_checks.h"
#include "common/cli_usage.h"
#include "common/error.h"
#include "common/filesystem_failure.h"
#include "common/job_bounds.h"
#include "endorecon_version.h"
#include "worker/runtime/commands.h"
#include "worker/runtime/progress_line.h"

int main(int argc, char** argv) {
  CLI::App app{"endorecon-worker: reconstruct endoscopic clips, or serve jobs from endorecon-server"};
  app.require_subcommand(1);
  app.set_version_flag("--version", ENDORECON_VERSION);  // server and workers run at one version
  std::map<std::string, endorecon::worker::Command> commands;
  commands["synth"] = endorecon::worker::AddSynthCommand(app);
  commands["reconstruct"] = endorecon::worker::AddReconstructCommand(app);
  commands["render"] = endorecon::worker::AddRenderCommand(app);
  commands["serve"] = endorecon::worker::AddServeCommand(app);
  commands["prepare"] = endorecon::worker::AddPrepareCommand(app);
  commands["calibrate"] = endorecon::worker::AddCalibrateCommand(app);
  commands["to-dicom"] = endorecon::worker::AddToDicomCommand(app);
  endorecon::DecimalIntegers(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // A mistyped command or option is named, with the nearest known one (CLI11 said "A subcommand is
    // required" of a mistyped command).
    return endorecon::ExplainParseError(app, e, argc, argv);
  }
  // The commands (synth, reconstruct, prepare, ...) log to stderr, as their progress goes: `synth DIR
  // > /dev/null` hid a failure's message (found 2026-12-06). `serve`, a service, logs to stdout for
  // its supervisor, as the server does.
  if (!app.got_subcommand("serve")) {
    spdlog::set_default_logger(
        std::make_shared<spdlog::logger>("", std::make_shared<spdlog::sinks::stderr_color_sink_mt>()));
  }
  endorecon::worker::EndProgressBeforeEachLog();
  try {
    for (auto* sub : app.get_subcommands()) return commands.at(sub->get_name())();
  } catch (const endorecon::Error& e) {
    spdlog::error("{}: {}", endorecon::ErrorCodeName(e.code()), endorecon::PrintableLines(e.what()));
    // A clip or file the command was given that is not there is the user's input, as a bad one is.
    // Credentials the server refused are 10 and 11, as the CLI's: a service manager keeps from
    // restarting a worker that will be refused again (deploy/systemd, RestartPreventExitStatus).
    switch (e.code()) {
      case endorecon::ErrorCode::kInvalidArgument:
      case endorecon::ErrorCode::kNotFound:
        return 2;
      case endorecon::ErrorCode::kUnauthenticated:
        return 10;
      case endorecon::ErrorCode::kPermissionDenied:
        return 11;
      default:
        return 1;
    }
  } catch (const std::filesystem::filesystem_error& e) {
    // A local file or folder the system refused: the path and why (it said "filesystem error:
    // status: Permission denied [PATH]"; found 2026-12-07); one the user named is input, exit 2.
    spdlog::error("{}", endorecon::PrintableLines(endorecon::DescribeFilesystemError(e)));
    return endorecon::IsUsersFileProblem(e.code().value()) ? 2 : 1;
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return 1;
  }
  return 0;
}
