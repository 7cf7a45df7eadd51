// PrepareFlags (as typed by a user, or carried by a job) to PrepareOptions.
#pragma once

#include <filesystem>

#include "common/prepare_flags.h"
#include "worker/prepare/prepare_clip.h"

namespace endorecon::prepare {

// Checks the flags (CheckPrepareFlags) and converts them; relative paths are taken under `base`
// (a job's downloaded recording), or as they are when `base` is empty. `out` is left empty.
PrepareOptions OptionsFromFlags(const PrepareFlags& flags, const std::filesystem::path& base = {});

}  // namespace endorecon::prepare
