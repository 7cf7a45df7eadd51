// The subcommands of endorecon-server besides serving: `token create|list|revoke` and
// `retention --dry-run`. Each registers itself on the CLI11 app and returns the callback that runs
// it (returning the process exit code). They work on the data folder directly, also while a
// server runs on it (the stores are SQLite in WAL mode).
#pragma once

#include <functional>

namespace CLI {
class App;
}

namespace endorecon::server {

using Command = std::function<int()>;

Command AddTokenCommand(CLI::App& app);
Command AddRetentionCommand(CLI::App& app);

}  // namespace endorecon::server
