// endorecon submit CLIP [options]: upload the clip folder (the files its layout names; only what the server
// lacks, resuming a partial upload), queue a reconstruction, optionally wait for it. With a raw stereo
// recording instead of CLIP (--left L --right R --calibration C ..., prepare's flags), the recording's files
// are uploaded and the worker prepares the clip before reconstructing it, in the same job.
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "client/clip_check.h"
#include "client/clip_cut.h"
#include "client/commands.h"
#include "client/exit_codes.h"
#include "client/interrupt_note.h"
#include "client/job_format.h"
#include "client/job_watcher.h"
#include "client/recording_upload.h"
#include "common/cli_checks.h"
#include "common/clip_files.h"
#include "common/dicom_file.h"
#include "common/dicom_values.h"
#include "common/error.h"
#include "common/file_read.h"
#include "common/file_upload.h"
#include "common/grpc_status.h"
#include "common/job_bounds.h"
#include "common/json_file.h"
#include "common/manifest.h"
#include "common/prepare_flags_cli.h"
#include "common/prepare_flags_proto.h"
#include "common/recording_flags_cli.h"
#include "common/transport_security.h"

namespace endorecon::client {
namespace {

struct SubmitFlags {
  std::string clip;
  std::string pacs, study_uid, series_uid;
  std::vector<std::string> send_to;
  v1::RecordingOptions recording;
  v1::DicomOutputOptions dicom;
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
  PrepareFlags raw;  // a raw stereo recording instead of CLIP (its --frames also picks a DICOM window)
};

std::string ReadFile(const std::string& path) {
  RequireRegularFile(path);
  std::ifstream in(path, std::ios::binary);
  if (!in) Fail(ErrorCode::kNotFound, "cannot read config file " + path);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

v1::ReconstructionOptions OptionsOf(const SubmitFlags& flags) {
  v1::ReconstructionOptions options;
  if (!flags.config.empty()) {
    options.set_config_json(ReadFile(flags.config));
    if (options.config_json().size() > kMaxConfigBytes) {
      FailInvalid("--config " + flags.config + ": " + std::to_string(options.config_json().size()) +
                  " bytes; at most " + std::to_string(kMaxConfigBytes));
    }
    if (!ParseJson(options.config_json(), "--config " + flags.config).is_object())
      FailInvalid("--config " + flags.config + ": not a JSON object (as config.json's \"train\")");
  }
  options.set_preset(flags.preset);
  if (flags.iterations >= 0) options.set_iterations(flags.iterations);
  options.set_time_budget_s(flags.time_budget_s);
  if (flags.holdout >= 0) options.set_holdout(flags.holdout);
  options.set_seed(flags.seed);
  options.set_force_static(flags.force_static);
  return options;
}

// The files under `dir` that `listing` leaves out, by their relative paths (a walk that follows no
// linked folder and skips what it cannot read: it only names what stays here).
std::vector<std::string> LeftOut(const std::filesystem::path& dir, const v1::Manifest& listing) {
  std::set<std::string> listed;
  for (const auto& file : listing.files()) listed.insert(file.path());
  std::vector<std::string> left;
  std::error_code error;
  for (std::filesystem::recursive_directory_iterator
           it(dir, std::filesystem::directory_options::skip_permission_denied, error),
       end;
       !error && it != end; it.increment(error)) {
    std::error_code type_error;
    if (!it->is_regular_file(type_error)) continue;
    const std::string relative = it->path().lexically_relative(dir).generic_string();
    if (!listed.count(relative)) left.push_back(relative);
  }
  std::sort(left.begin(), left.end());
  return left;
}

// The clip folder's files its layout names (ListClipFiles), paths and sizes; what no loader reads
// (notes, a video, a spreadsheet beside the frames) stays on this machine, and is named on stderr
// (with --json too: stdout is the job's JSON, and a script's log should say what stayed here).
v1::Manifest ListingOfClipFolder(const std::filesystem::path& clip) {
  v1::Manifest listing;
  try {
    listing = ListingOfFiles(clip, ListClipFiles(clip));
  } catch (const Error& e) {
    Fail(e.code(), std::string(e.what()) + " (found before the upload: nothing was sent)");
  }
  // Names as printable text: a file named "a\nuploaded 0 file(s)\e[31m" printed a line of its own.
  const std::vector<std::string> left = LeftOut(clip, listing);
  if (!left.empty()) {
    std::cerr << "left out " << left.size() << " file(s) under " << PrintableText(clip.string(), 4096)
              << " that the clip's layout does not name (docs/formats.md), not uploaded:";
    constexpr std::size_t kNamed = 10;
    for (std::size_t i = 0; i < std::min(left.size(), kNamed); ++i)
      std::cerr << (i ? ", " : " ") << PrintableText(left[i], 4096);
    if (left.size() > kNamed) std::cerr << " and " << left.size() - kNamed << " more";
    std::cerr << "\n";
  }
  return listing;
}

// A clip folder goes up as the files its layout names (ListingOfClipFolder; a cut to --frames is
// itself such a folder, its left-out files said of the user's folder). A folder of DICOM files goes
// up whole; a single file (a DICOM recording) as itself, named by its file name. Paths and sizes
// only: the digests come after the server has seen the sizes.
v1::Manifest ListingOfClip(const std::filesystem::path& clip, bool clip_folder) {
  if (clip_folder) return ListingOfClipFolder(clip);
  if (!std::filesystem::is_regular_file(clip)) return ListingOfDirectory(clip);
  v1::Manifest manifest;
  auto* entry = manifest.add_files();
  entry->set_path(clip.filename().string());
  entry->set_size(static_cast<std::int64_t>(std::filesystem::file_size(clip)));
  return manifest;
}

// Asks the server whether a clip of these sizes may come (its upload limit, the tenant's quotas)
// before the files are read for their digests: a 50 GB file was hashed for minutes, then refused.
// A refusal for size names the largest file (the server's message).
void CheckSizes(const Globals& globals, v1::JobService::Stub& stub, const v1::Manifest& listing) {
  v1::UploadStatus status;
  auto context = CallContext(globals.timeout());
  ThrowIfFailed(stub.QueryUpload(context.get(), listing, &status), "upload query");
}

// Asks the server to check the job as it would be submitted, with the clip's listing, before the
// upload: options it refuses (an unknown --send-to PACS, a quota of jobs) were found after it.
void CheckJob(const Globals& globals, v1::JobService::Stub& stub, v1::SubmitRequest request,
              const v1::Manifest& listing) {
  *request.mutable_clip() = listing;
  request.set_validate_only(true);
  v1::Job job;
  auto context = CallContext(globals.timeout());
  ThrowIfFailed(stub.Submit(context.get(), request, &job), "submit (checked before the upload)");
}

// On a terminal, an upload's progress on one line of stderr, rewritten at most four times a second:
// 10,001 small files took minutes in silence and read as a hang (found 2026-12-06). Erased when the
// upload is done; ended with a newline when it fails, so the error stands on a line of its own.
class UploadProgressLine {
 public:
  explicit UploadProgressLine(bool on) : on_(on) {}
  UploadProgressLine(const UploadProgressLine&) = delete;
  UploadProgressLine& operator=(const UploadProgressLine&) = delete;
  ~UploadProgressLine() {
    if (drawn_) std::cerr << "\n" << std::flush;
  }
  void Show(std::int64_t sent, std::int64_t to_send) {
    const auto now = std::chrono::steady_clock::now();
    if (!on_ || (drawn_ && sent < to_send && now - shown_ < std::chrono::milliseconds(250))) return;
    shown_ = now;
    drawn_ = true;
    std::cerr << "\ruploading: " << HumanBytes(sent) << " of " << HumanBytes(to_send) << " ("
              << (to_send > 0 ? 100 * sent / to_send : 100) << "%)\033[K" << std::flush;
  }
  void Erase() {
    if (drawn_) std::cerr << "\r\033[K" << std::flush;
    drawn_ = false;
  }

 private:
  bool on_;
  bool drawn_ = false;
  std::chrono::steady_clock::time_point shown_;
};

// Uploads the clip (what the server lacks of it) and returns its manifest. Its sizes and the job
// (`request`, without its clip) are checked by the server first, then a clip folder (not a DICOM
// recording nor a raw one) here (clip_check.h).
v1::Manifest Upload(const Globals& globals, v1::JobService::Stub& stub, const std::filesystem::path& clip,
                    bool clip_folder, const v1::SubmitRequest& request) {
  auto manifest = ListingOfClip(clip, clip_folder);
  // The manifest with its digests (64 characters and a tag each) travels in one message: a clip of
  // 120,000 files was refused as "Sent message larger than max", naming its largest file.
  const std::size_t manifest_bytes = manifest.ByteSizeLong() + std::size_t(manifest.files_size()) * 66;
  if (manifest_bytes > MostManifestBytes()) {
    FailInvalid(clip.string() + ": " + std::to_string(manifest.files_size()) +
                " files; their manifest would take " + std::to_string(manifest_bytes) +
                " bytes, more than the service's messages carry (" + std::to_string(MostManifestBytes()) +
                ", about " +
                std::to_string(MostManifestBytes() * std::size_t(manifest.files_size()) / manifest_bytes) +
                " files of these names): send fewer files (a recording as one video or DICOM file, not its "
                "frames) (found before the upload: nothing was sent)");
  }
  // A clip whose results no call could hand back would train for nothing (found 2026-12-06).
  if (clip_folder) {
    const nlohmann::json config = request.options().config_json().empty()
                                      ? nlohmann::json::object()
                                      : ParseJson(request.options().config_json(), "--config");
    try {
      CheckResultsFit(ListClipFrames(clip).size(), WritesUncertaintyMaps(config), manifest_bytes,
                      clip.string());
    } catch (const Error& e) {
      FailInvalid(std::string(e.what()) + " (found before the upload: nothing was sent)");
    }
  }
  const auto root = std::filesystem::is_regular_file(clip) ? clip.parent_path() : clip;
  CheckSizes(globals, stub, manifest);
  CheckJob(globals, stub, request, manifest);
  if (clip_folder) CheckClipBeforeUpload(clip);
  AddDigests(root.empty() ? "." : root, manifest);
  UploadCalls calls;
  calls.query = [&](grpc::ClientContext* context, const v1::Manifest& m, v1::UploadStatus* status) {
    return stub.QueryUpload(context, m, status);
  };
  calls.open = [&](grpc::ClientContext* context, v1::UploadStatus* status) {
    return stub.Upload(context, status);
  };
  UploadOptions upload_options;
  upload_options.call_timeout = globals.timeout();
  // Ctrl-C mid-upload said nothing, and a user did not know that running it again resumes.
  const InterruptNote interrupt_note(
      "upload interrupted; what arrived is kept on the server (and counts against your tenant's bytes) until "
      "the server's --orphan-hours: run the same `endorecon submit` again to resume it, or "
      "`endorecon uploads --drop` to give it up");
  UploadProgressLine progress(!globals.json && isatty(STDERR_FILENO) != 0);
  upload_options.on_progress = [&](std::int64_t sent, std::int64_t to_send) { progress.Show(sent, to_send); };
  const auto upload = [&] {
    try {
      return UploadFiles(root.empty() ? "." : root, manifest, calls, upload_options);
    } catch (const Error& e) {
      // A server gone or a deadline passed mid-upload said only "Socket closed" (found 2026-12-06).
      if (e.code() != ErrorCode::kUnavailable) throw;
      Fail(e.code(), std::string(e.what()) +
                         "; what arrived is kept on the server: run the same `endorecon submit` again to "
                         "resume the upload");
    }
  }();
  progress.Erase();
  if (!globals.json) {
    std::cerr << "uploaded " << manifest.files_size() << " file(s): " << HumanBytes(upload.bytes_sent)
              << " sent, " << HumanBytes(upload.bytes_skipped) << " already on the server\n";
  }
  if (!upload.status.complete())
    Fail(ErrorCode::kUnavailable, "the upload is incomplete; run submit again to resume");
  return manifest;
}

int Submit(const Globals& globals, const SubmitFlags& flags) {
  const auto options = OptionsOf(flags);
  if (!flags.clip.empty() + !flags.pacs.empty() + !flags.raw.empty() != 1) {
    FailInvalid(
        "submit takes a CLIP (folder or DICOM recording), a raw recording (--left/--right, --side-by-side "
        "or --top-bottom) or --pacs NAME --study UID: exactly one of them");
  }
  if (!flags.pacs.empty() && flags.study_uid.empty()) FailInvalid("--pacs needs --study UID");
  // A DICOM file, or a folder holding one (read once: a folder's files are opened to tell).
  const bool recording = !flags.clip.empty() && dicom::HoldsDicom(flags.clip);
  // A single file goes up as a DICOM recording: one that is not (a video, say) is refused before its
  // upload, not by the worker after it.
  if (!flags.clip.empty() && std::filesystem::is_regular_file(flags.clip) && !recording) {
    FailInvalid(
        flags.clip +
        ": a file that is not a DICOM recording (no \"DICM\" at byte 128, not named *.dcm): CLIP is a "
        "clip folder (EndoNeRF or transforms.json layout) or a DICOM recording; a video becomes one "
        "with `endorecon-worker to-dicom VIDEO -o recording.dcm`, and a stereo video can go as a raw "
        "recording (--side-by-side VIDEO --calibration FILE)");
  }
  // A folder that is no clip is refused before its upload, by the rule the worker's loader applies
  // first (common/clip_files.h): it was uploaded and queued, then failed on the worker.
  const bool clip_folder = !flags.clip.empty() && std::filesystem::is_directory(flags.clip) && !recording;
  if (clip_folder && !FindClipLayout(flags.clip)) {
    FailInvalid(flags.clip +
                ": not a clip: found neither transforms.json (transforms.json layout) nor poses_bounds.npy "
                "(EndoNeRF layout), and no DICOM recording (docs/formats.md) (found before the upload: "
                "nothing was sent)");
  }
  if (flags.raw.empty() && !flags.raw.size.empty()) ParseFrameSize(flags.raw.size);  // before any upload
  if (flags.raw.empty() && !flags.raw.frames.empty()) ParseFrameRange(flags.raw.frames);
  // prepare's options shape a raw recording only: with a clip, a DICOM recording or a PACS study they
  // were ignored without a word.
  const PrepareFlags& raw = flags.raw;
  if (raw.empty() && (!raw.calibration.empty() || raw.rectified || raw.focal != 0 || raw.baseline != 0 ||
                      !raw.masks.empty() || raw.mask_tool != "white" || !raw.exclude.empty() ||
                      !raw.poses.empty() || raw.estimate_poses || raw.depth_refine || raw.depth_paths != 0 ||
                      raw.skip_left != 0 || raw.skip_right != 0)) {
    FailInvalid(
        "--calibration, --rectified, --focal, --baseline, --masks, --mask-tool, --exclude, --poses, "
        "--estimate-poses, --depth-refine, --depth-paths, --skip-left and --skip-right prepare a raw "
        "recording (--left/--right, "
        "--side-by-side or --top-bottom); a clip folder, a DICOM recording or a PACS study takes none");
  }
  if (!flags.name.empty()) ValidateJobName(flags.name);  // as the server would, after the upload
  dicom::CheckDicomResultFlags(flags.dicom.enabled(), !flags.pacs.empty() || recording,
                               flags.dicom.patient_id(), flags.dicom.patient_name(), flags.dicom.study_uid());
  if (flags.pacs.empty() && (!flags.study_uid.empty() || !flags.series_uid.empty()))
    FailInvalid("--study and --series name a recording in a PACS: they go with --pacs NAME");
  // A clip folder is used as it is: the recording's options are refused before its upload (as the
  // worker would after it).
  if (clip_folder && (!flags.raw.size.empty() || flags.recording.fps() > 0 ||
                      !flags.recording.stereo().empty() || !flags.recording.endoscope().empty())) {
    FailInvalid("--size, --fps, --stereo and --endoscope apply to a DICOM recording, and " + flags.clip +
                " is a clip folder, whose frames are used as they are (--frames picks some)");
  }
  // A file named *.dcm that is no DICOM file is refused by the server's first look: here, before its
  // upload (a 200 MB folder went up to be refused; found 2026-12-07).
  if (recording) {
    std::vector<std::filesystem::path> files{flags.clip};
    if (std::filesystem::is_directory(flags.clip)) {
      files.clear();
      for (const auto& entry : std::filesystem::directory_iterator(flags.clip)) files.push_back(entry.path());
    }
    for (const auto& file : files) {
      if (std::filesystem::is_regular_file(file) && dicom::HasDicomExtension(file) &&
          !dicom::IsDicomFile(file)) {
        FailInvalid(
            file.string() +
            ": not a DICOM file (no \"DICM\" at byte 128) (found before the upload: nothing was sent)");
      }
    }
  }
  // A raw recording is staged under canonical names (recording_upload.h); its folder is uploaded.
  std::optional<StagedRecording> staged;
  if (!flags.raw.empty()) {
    staged.emplace(flags.raw);
    try {
      staged->CheckBeforeUpload();
    } catch (const Error& e) {
      Fail(e.code(), std::string(e.what()) + " (found before the upload: nothing was sent)");
    }
  }
  // A clip folder's picked frames go up alone, as a clip cut to them (clip_cut.h); the worker loads
  // it as it is, and the job's recording.frames records which they were.
  FrameRange frames = ParseFrameRange(flags.raw.frames);
  std::optional<StagedClipCut> cut;
  if (clip_folder && !frames.SelectsAll()) {
    try {
      cut.emplace(flags.clip, frames);
    } catch (const Error& e) {
      Fail(e.code(), std::string(e.what()) + " (found before the upload: nothing was sent)");
    }
    if (cut->picked() == cut->total()) {  // 0:99999 of a clip of 12: the clip as it is
      cut.reset();
      frames = FrameRange{};
    } else {
      std::cerr << "uploading frames " << frames.ToString() << " of " << PrintableText(flags.clip, 4096)
                << ": " << cut->picked() << " of its " << cut->total() << " frames\n";
      // The cut holds the layout's files alone: what the user's folder holds beyond them is said
      // here (it went unsaid with --frames; found 2026-12-07).
      ListingOfClipFolder(flags.clip);
    }
  }
  const auto stub = globals.Connect();
  v1::SubmitRequest request;
  if (!flags.pacs.empty()) {
    request.mutable_pacs()->set_pacs(flags.pacs);
    request.mutable_pacs()->set_study_uid(flags.study_uid);
    request.mutable_pacs()->set_series_uid(flags.series_uid);
  }
  if (staged) {
    *request.mutable_prepare() = PrepareFlagsToProto(staged->flags());
    for (const auto& [name, path] : staged->sources())
      (*request.mutable_prepare()->mutable_sources())[name] = path;
  } else {
    *request.mutable_recording() = flags.recording;
    // A DICOM recording's window, or the frames a clip folder was cut to, as config.json and the
    // checkpoints write them ("::2" is "0::2").
    if (!frames.SelectsAll()) request.mutable_recording()->set_frames(frames.ToString());
    request.mutable_recording()->set_size(flags.raw.size);
  }
  *request.mutable_options() = options;
  *request.mutable_dicom() = flags.dicom;
  for (const auto& name : flags.send_to) request.add_send_to(name);
  request.set_priority(flags.priority);
  const std::string default_name = staged               ? staged->name()
                                   : flags.clip.empty() ? "pacs " + flags.pacs
                                                        : PathName(flags.clip);
  // A folder's name is no chosen name: made valid, not refused after the upload (a newline in it was).
  request.set_name(flags.name.empty() ? ValidJobName(default_name) : flags.name);
  if (flags.pacs.empty()) {
    try {
      *request.mutable_clip() = Upload(globals, *stub,
                                       staged ? staged->dir()
                                       : cut  ? cut->dir()
                                              : std::filesystem::path(flags.clip),
                                       clip_folder, request);
    } catch (const Error& e) {
      if (!cut) throw;
      Fail(e.code(), cut->InClip(e.what()));  // the user's files, not their links in the cut
    }
    cut.reset();  // uploaded: the links go now, not when a --wait ends
  }
  v1::Job job;
  auto context = CallContext(globals.timeout());
  try {
    ThrowIfFailed(stub->Submit(context.get(), request, &job), "submit");
  } catch (const Error& e) {
    if (!flags.pacs.empty()) throw;
    // Refused after the upload (a submit beside it took the tenant's last job slot, or the server's
    // checks changed in between): what was sent stays, and counts toward the tenant's bytes; said,
    // as a Ctrl-C mid-upload says it (found by a multi-tenant walk-through, 2026-12-06).
    // A refusal of the files themselves is not undone by the same submit (found 2026-12-07): said as
    // "correct what it names".
    Fail(e.code(),
         std::string(e.what()) +
             "\nendorecon: what was uploaded is kept on the server (and counts against your "
             "tenant's bytes) until the server's --orphan-hours: correct what the message names and "
             "run `endorecon submit` again (files already there are not sent again), or `endorecon "
             "uploads --drop` to give it up");
  }
  if (globals.json) {
    std::cout << ToJson(job) << std::endl;
  } else {
    std::cout << "job " << job.id() << " queued (priority " << job.priority() << ")" << std::endl;
  }
  if (!flags.wait) return kExitOk;
  // The job is the server's now: a watch that gives up (a long outage) says how to pick it up again.
  const auto done = WatchJob(globals, job.id(), {flags.previews});
  // A send the job was submitted with that failed fails the command, as `send --wait` does: the
  // results did not reach the PACS.
  for (const auto& send : done.sends()) {
    if (done.state() == v1::SUCCEEDED && send.state() == v1::DicomSend::SEND_FAILED) return kExitJobFailed;
  }
  return ExitCodeFor(done.state());
}

}  // namespace

Command AddSubmitCommand(CLI::App& app) {
  auto flags = std::make_shared<SubmitFlags>();
  auto* sub = app.add_subcommand(
      "submit",
      "upload a clip folder, a DICOM recording or a raw stereo recording (prepared by the worker), or "
      "name a recording in a PACS, and queue its reconstruction");
  sub->add_option(
      "CLIP", flags->clip,
      "clip folder (EndoNeRF layout or transforms.json), or a DICOM recording (a file, or a folder of "
      "DICOM files); or give a raw recording or --pacs");
  AddPrepareFlags(*sub, flags->raw);
  sub->add_option("--pacs", flags->pacs,
                  "instead of CLIP: retrieve the recording from this PACS (server's name)");
  sub->add_option("--study", flags->study_uid, "with --pacs: the recording's Study Instance UID");
  sub->add_option("--series", flags->series_uid, "with --pacs: only this series of the study");
  sub->add_option("--send-to", flags->send_to,
                  "send the DICOM results to this PACS when the job succeeds (repeatable)");
  AddRecordingFlags(*sub, flags->recording);
  AddDicomResultFlags(*sub, flags->dicom);
  sub->add_option("--config", flags->config,
                  "JSON file overriding the preset (as endorecon-worker reconstruct)");
  sub->add_option("--preset", flags->preset, "cpu, gpu or paper (default: the worker's, cpu)")
      ->check(CLI::IsMember({"cpu", "gpu", "paper"}));
  sub->add_option("--iterations", flags->iterations, "training iterations (default: the preset's)")
      ->check(AboveZero());
  sub->add_option("--time-budget", flags->time_budget_s,
                  "seconds for the whole run on the worker: training, evaluation, writing (0: none)")
      ->check(TimeBudget());
  sub->add_option("--holdout", flags->holdout,
                  "hold out every K-th frame (0: none, else K >= 2; default: the preset's)")
      ->check(HoldoutSpacing());
  sub->add_option("--seed", flags->seed, "random seed")->check(AtLeastZero());
  sub->add_flag("--static", flags->force_static, "treat the clip as static (no deformation)");
  sub->add_option("--priority", flags->priority, "higher runs first, -100 to 100 (default 0)")
      ->check(CLI::Range(-kMaxPriority, kMaxPriority));
  sub->add_option("--name", flags->name,
                  "a name to recognise the job by (default: the clip's or recording's name; for "
                  "--left/--right the folder holding both)");
  auto* wait = sub->add_flag("--wait", flags->wait,
                             "watch the job until it finishes; exit code tells how it ended (5 also when a "
                             "--send-to send failed)");
  sub->add_option("--previews", flags->previews, "with --wait: save previews into this folder")->needs(wait);
  return [flags](const Globals& globals) { return Submit(globals, *flags); };
}

}  // namespace endorecon::client
