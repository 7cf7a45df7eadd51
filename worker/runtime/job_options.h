// How a leased job's options become the engine's: the clip and results folders of the job's scratch
// folder, its configuration (the job's JSON, parsed here: the engine takes the object itself), the
// reconstruction flags, the device's thread count and the checkpoint to resume from.
#pragma once

#include <filesystem>

#include "endorecon/v1/job.pb.h"
#include "worker/engine/reconstruct.h"
#include "worker/runtime/device_list.h"

namespace endorecon::worker {

// Throws Error(kInvalidArgument) when the job's config is not a JSON object (the job then fails for
// good: retrying cannot mend it).
ReconstructOptions OptionsFor(const v1::Job& job, const std::filesystem::path& job_dir, const Device& device);

}  // namespace endorecon::worker
