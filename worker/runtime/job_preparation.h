// The preparation phase of a job submitted as a raw stereo recording (Job.prepare, issue 16): the
// downloaded recording becomes a clip inside the results folder (out/clip/, so it is part of the
// results), while progress goes out as phase "prepare" (frames done of the selected) and the
// clip's preview.png goes out once as a "prepare" preview.
#pragma once

#include <filesystem>
#include <functional>

#include "endorecon/v1/job.pb.h"
#include "worker/runtime/progress_reporter.h"

namespace endorecon::worker {

// Returns the prepared clip's folder. Throws the preparation's errors (kInvalidArgument for a bad
// recording, which fails the job; kCancelled when `should_stop` said so).
std::filesystem::path PrepareJobRecording(const v1::Job& job, const std::filesystem::path& recording_dir,
                                          const std::filesystem::path& out_dir, ProgressReporter& reporter,
                                          const std::function<bool()>& should_stop);

}  // namespace endorecon::worker
