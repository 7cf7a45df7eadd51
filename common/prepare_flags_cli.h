// The command-line flags of PrepareFlags, registered the same way on `endorecon-worker prepare`
// and on `endorecon submit` (which uploads the recording and prepares it in the job).
#pragma once

#include "common/prepare_flags.h"

namespace CLI {
class App;
}

namespace endorecon {

// Registers --left --right --side-by-side --top-bottom --calibration --rectified --focal --baseline
// --masks --mask-tool --exclude --frames --size --poses --estimate-poses
// --depth-refine --depth-paths on `cmd`, writing into `flags` (which must outlive parsing).
void AddPrepareFlags(CLI::App& cmd, PrepareFlags& flags);

}  // namespace endorecon
