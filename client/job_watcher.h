// Follows a job's Watch stream until the job is finished (used by `watch` and `submit --wait`):
// a live progress line on a terminal, one line per event otherwise, JSON Lines with --json.
// Each stream has a deadline; when it runs out, or the server restarts, the watch reconnects.
#pragma once

#include <string>

#include "client/commands.h"

namespace endorecon::client {

struct WatchOptions {
  std::string previews_dir;  // non-empty: save previews there as <kind>-it<iteration>.png
  double stream_s = 300;     // deadline of each Watch stream before it is reopened
};

// Returns the finished job. Throws Error when the job does not exist or the server stays
// unreachable for longer than the globals' timeout.
v1::Job WatchJob(const Globals& globals, const std::string& id, const WatchOptions& options);

}  // namespace endorecon::client
