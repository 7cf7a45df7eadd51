// Each `endorecon-worker` subcommand registers itself on the CLI11 app and returns the callback
// that runs it (returning the process exit code). One file per subcommand.
#pragma once

#include <functional>

namespace CLI {
class App;
}

namespace endorecon::worker {

using Command = std::function<int()>;

Command AddSynthCommand(CLI::App& app);
Command AddReconstructCommand(CLI::App& app);
Command AddRenderCommand(CLI::App& app);
Command AddServeCommand(CLI::App& app);
Command AddPrepareCommand(CLI::App& app);
Command AddCalibrateCommand(CLI::App& app);
Command AddToDicomCommand(CLI::App& app);

}  // namespace endorecon::worker
