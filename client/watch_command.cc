// endorecon watch JOB: follow a job live until it finishes.
#include <CLI/CLI.hpp>

#include "client/commands.h"
#include "client/exit_codes.h"
#include "client/job_watcher.h"

namespace endorecon::client {

Command AddWatchCommand(CLI::App& app) {
  auto id = std::make_shared<std::string>();
  auto options = std::make_shared<WatchOptions>();
  auto* sub = app.add_subcommand("watch", "follow a job: progress bar with PSNR and ETA, until it finishes");
  sub->add_option("JOB", *id, "job id")->required();
  sub->add_option("--previews", options->previews_dir,
                  "save the rendered and uncertainty previews in this folder");
  return
      [id, options](const Globals& globals) { return ExitCodeFor(WatchJob(globals, *id, *options).state()); };
}

}  // namespace endorecon::client
