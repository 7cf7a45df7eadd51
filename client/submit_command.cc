// endorecon submit CLIP [options]: upload the clip folder (only what the server lacks, resuming a
// partial upload), queue a reconstruction, optionally wait for it. With a raw stereo recording
// instead of CLIP (--left L --right R --calibration C ..., prepare's flags), the recording's files
// are uploaded and the worker prepares the clip before reconstructing it, in the same job.
#include <CLI/CLI.hpp>
#include <fstream>
#include <iostream>
#include <optional>
#include <sstream>

#include "client/commands.h"
#include "client/exit_codes.h"
#include "client/job_format.h"
#include "client/job_watcher.h"
#include "client/recording_upload.h"
#include "common/error.h"
#include "common/file_upload.h"
#include "common/grpc_status.h"
#include "common/manifest.h"
#include "common/prepare_flags_cli.h"
#include "common/prepare_flags_proto.h"
#include "common/transport_security.h"

namespace endorecon::client {
namespace {

struct SubmitFlags {
  std::string clip;
  std::string config;
  std::string preset;
  int iterations = -1;
  double time_budget_s = 0;
  int holdout = -1;
  std::uint64_t seed = 0;
  bool force_static = false;
  int priority = 0;
  std::string name;
  bool wait = false;
  std::string previews;
  PrepareFlags recording;  // a raw recording instead of CLIP
};

std::string ReadFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) Fail(ErrorCode::kNotFound, "cannot read config file " + path);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

v1::ReconstructionOptions OptionsOf(const SubmitFlags& flags) {
  v1::ReconstructionOptions options;
  if (!flags.config.empty()) options.set_config_json(ReadFile(flags.config));
  options.set_preset(flags.preset);
  if (flags.iterations >= 0) options.set_iterations(flags.iterations);
  options.set_time_budget_s(flags.time_budget_s);
  if (flags.holdout >= 0) options.set_holdout(flags.holdout);
  options.set_seed(flags.seed);
  options.set_force_static(flags.force_static);
  return options;
}

int Submit(const Globals& globals, const SubmitFlags& flags) {
  const auto options = OptionsOf(flags);
  if (flags.clip.empty() == flags.recording.empty()) {
    FailInvalid(
        "give a CLIP folder, or a raw recording (--left/--right, --side-by-side or --top-bottom), not both");
  }
  // A recording is staged under canonical names (recording_upload.h); its folder is uploaded.
  std::optional<StagedRecording> staged;
  if (!flags.recording.empty()) staged.emplace(flags.recording);
  const std::filesystem::path folder = staged ? staged->dir() : std::filesystem::path(flags.clip);
  const auto manifest = ManifestOfDirectory(folder);
  const auto stub = globals.Connect();
  UploadCalls calls;
  calls.query = [&](grpc::ClientContext* context, const v1::Manifest& m, v1::UploadStatus* status) {
    return stub->QueryUpload(context, m, status);
  };
  calls.open = [&](grpc::ClientContext* context, v1::UploadStatus* status) {
    return stub->Upload(context, status);
  };
  UploadOptions upload_options;
  upload_options.call_timeout = globals.timeout();
  const auto upload = UploadFiles(folder, manifest, calls, upload_options);
  if (!globals.json) {
    std::cerr << "uploaded " << manifest.files_size() << " file(s): " << HumanBytes(upload.bytes_sent)
              << " sent, " << HumanBytes(upload.bytes_skipped) << " already on the server\n";
  }
  if (!upload.status.complete())
    Fail(ErrorCode::kUnavailable, "the upload is incomplete; run submit again to resume");

  v1::SubmitRequest request;
  *request.mutable_clip() = manifest;
  *request.mutable_options() = options;
  if (staged) *request.mutable_prepare() = PrepareFlagsToProto(staged->flags());
  request.set_priority(flags.priority);
  request.set_name(!flags.name.empty() ? flags.name
                   : staged            ? staged->name()
                            : std::filesystem::path(flags.clip).lexically_normal().filename().string());
  v1::Job job;
  auto context = CallContext(globals.timeout());
  ThrowIfFailed(stub->Submit(context.get(), request, &job), "submit");
  if (globals.json) {
    std::cout << ToJson(job) << std::endl;
  } else {
    std::cout << "job " << job.id() << " queued (priority " << job.priority() << ")" << std::endl;
  }
  if (!flags.wait) return kExitOk;
  const auto done = WatchJob(globals, job.id(), {flags.previews});
  return ExitCodeFor(done.state());
}

}  // namespace

Command AddSubmitCommand(CLI::App& app) {
  auto flags = std::make_shared<SubmitFlags>();
  auto* sub = app.add_subcommand("submit",
                                 "upload a clip folder (or a raw stereo recording, prepared by the worker) "
                                 "and queue its reconstruction");
  sub->add_option("CLIP", flags->clip,
                  "clip folder (EndoNeRF layout or transforms.json); or give a recording");
  AddPrepareFlags(*sub, flags->recording);
  sub->add_option("--config", flags->config,
                  "JSON file overriding the preset (as endorecon-worker reconstruct)");
  sub->add_option("--preset", flags->preset, "cpu or paper (default: the worker's, cpu)");
  sub->add_option("--iterations", flags->iterations, "training iterations (default: the preset's)");
  sub->add_option("--time-budget", flags->time_budget_s, "stop training after this many seconds (0: none)");
  sub->add_option("--holdout", flags->holdout, "hold out every K-th frame (0: none; default: the preset's)");
  sub->add_option("--seed", flags->seed, "random seed");
  sub->add_flag("--static", flags->force_static, "treat the clip as static (no deformation)");
  sub->add_option("--priority", flags->priority, "higher runs first (default 0)");
  sub->add_option("--name", flags->name, "a name to recognise the job by (default: the folder's)");
  sub->add_flag("--wait", flags->wait, "watch the job until it finishes; exit code tells how it ended");
  sub->add_option("--previews", flags->previews, "with --wait: save previews into this folder");
  return [flags](const Globals& globals) { return Submit(globals, *flags); };
}

}  // namespace endorecon::client
