#include "worker/runtime/job_preparation.h"

#include <spdlog/spdlog.h>

#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>
#include <sstream>

#include "common/prepare_flags_proto.h"
#include "common/replace_all.h"
#include "worker/prepare/options_from_flags.h"

namespace endorecon::worker {
namespace {

namespace fs = std::filesystem;

// prepare.json names the recording's files where the worker staged them (its scratch folder): each
// is replaced by the file or folder as the submitter named it (PrepareOptions.sources), so the
// clip that comes back with the results says where it came from.
void NameTheSubmittersFiles(const fs::path& report, const fs::path& recording_dir, const v1::Job& job) {
  std::ifstream in(report);
  nlohmann::json json = nlohmann::json::parse(in, nullptr, false);
  in.close();
  if (json.is_discarded()) return;
  const std::function<void(nlohmann::json&)> rename = [&](nlohmann::json& value) {
    if (value.is_structured()) {
      for (auto& child : value) rename(child);
      return;
    }
    if (!value.is_string()) return;
    std::string text = value.get<std::string>();
    for (const auto& [staged, given] : job.prepare().sources()) {
      const bool folder = !staged.empty() && staged.back() == '/';
      const std::string from =
          (recording_dir / (folder ? staged.substr(0, staged.size() - 1) : staged)).string();
      const std::string to =
          folder && !given.empty() && given.back() == '/' ? given.substr(0, given.size() - 1) : given;
      text = ReplaceAll(std::move(text), from, to);
    }
    value = text;
  };
  rename(json);
  std::ofstream(report) << json.dump(1) << "\n";
}

}  // namespace

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
  NameTheSubmittersFiles(options.out / "prepare.json", recording_dir, job);
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
