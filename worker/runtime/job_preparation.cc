#include "worker/runtime/job_preparation.h"

#include <spdlog/spdlog.h>

#include <fstream>
#include <sstream>

#include "common/prepare_flags_proto.h"
#include "worker/prepare/options_from_flags.h"

namespace endorecon::worker {

std::filesystem::path PrepareJobRecording(const v1::Job& job, const std::filesystem::path& recording_dir,
                                          const std::filesystem::path& out_dir, ProgressReporter& reporter,
                                          const std::function<bool()>& should_stop) {
  prepare::PrepareOptions options =
      prepare::OptionsFromFlags(PrepareFlagsFromProto(job.prepare()), recording_dir);
  options.out = out_dir / "clip";
  prepare::PrepareHooks hooks;
  hooks.should_stop = should_stop;
  hooks.on_frame = [&](int done, int total) {
    v1::Progress progress;
    progress.set_phase("prepare");
    progress.set_iteration(done);
    progress.set_total_iterations(std::max(0, total));
    reporter.SetProgress(progress);
  };
  const prepare::PrepareSummary summary = prepare::PrepareClip(options, hooks);
  spdlog::info("job {}: prepared {} frames of the recording in {:.1f} s ({} layout)", job.id(),
               summary.frames, summary.seconds, summary.layout);
  std::ifstream png(options.out / "preview.png", std::ios::binary);
  std::ostringstream bytes;
  bytes << png.rdbuf();
  v1::Preview preview;
  preview.set_kind("prepare");
  preview.set_png(bytes.str());
  reporter.AddPreview(std::move(preview));
  return options.out;
}

}  // namespace endorecon::worker
