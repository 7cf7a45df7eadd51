#include "server/job_coordinator.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <set>
#include <thread>

#include "common/dicom/recording_layout.h"
#include "common/dicom/uid.h"
#include "common/dicom_values.h"
#include "common/error.h"
#include "common/job_bounds.h"
#include "common/job_results_text.h"
#include "common/json_file.h"
#include "common/manifest.h"
#include "common/prepare_flags_proto.h"
#include "server/job_states.h"
#include "server/recording_check.h"
#include "worker/engine/train/config_check.h"

namespace endorecon::server {
namespace {

void ValidateOptions(const v1::ReconstructionOptions& options) {
  if (!options.preset().empty() && options.preset() != "cpu" && options.preset() != "gpu" &&
      options.preset() != "paper") {
    FailInvalid("options.preset is '" + options.preset() + "'; expected 'cpu', 'gpu' or 'paper'");
  }
  if (options.has_iterations() && options.iterations() <= 0) {
    FailInvalid("options.iterations is " + std::to_string(options.iterations()) + "; expected > 0");
  }
  if (options.has_holdout() && (options.holdout() < 0 || options.holdout() == 1)) {
    FailInvalid("options.holdout is " + std::to_string(options.holdout()) +
                "; expected 0 (none held out) or K >= 2 (every K-th frame)");
  }
  if (!(options.time_budget_s() == 0 ||
        (options.time_budget_s() >= kLeastTimeBudgetS && options.time_budget_s() <= kMostTimeBudgetS))) {
    FailInvalid("options.time_budget_s is " + std::to_string(options.time_budget_s()) +
                "; expected 0 (no budget) or " + std::to_string(int(kLeastTimeBudgetS)) + " to " +
                std::to_string(int(kMostTimeBudgetS)) + " seconds (a week)");
  }
  if (options.config_json().size() > kMaxConfigBytes) {
    FailInvalid("options.config_json has " + std::to_string(options.config_json().size()) +
                " bytes; at most " + std::to_string(kMaxConfigBytes));
  }
  if (!options.config_json().empty()) {
    const auto config = ParseJson(options.config_json(), "options.config_json");
    if (!config.is_object()) FailInvalid("options.config_json is not a JSON object");
    // Its keys, types and bounds as the worker's engine takes them: a misspelt key failed the job only
    // when a worker leased it, after the upload and the queue.
    try {
      train::CheckConfigJson(config, options.preset().empty() ? "cpu" : options.preset());
    } catch (const Error& e) {
      FailInvalid(std::string("options.config_json (--config): ") + e.what());
    }
  }
}

void ValidateRecording(const v1::RecordingOptions& recording) {
  dicom::ParseStereoLayout(recording.stereo());
  ParseFrameRange(recording.frames());
  dicom::ParseEndoscope(recording.endoscope());
  if (!recording.size().empty()) ParseFrameSize(recording.size());
  if (!(recording.fps() >= 0))
    FailInvalid("recording.fps is " + std::to_string(recording.fps()) + "; expected >= 0");
}

bool Retrieving(const v1::Job& job) {
  return job.has_retrieval() && job.retrieval().state() == v1::Retrieval::RETRIEVING;
}

// Throws kFailedPrecondition naming the first file of `manifest` the blob store lacks.
// `usable` (BlobHolders::Holds of the tenant naming them, when given) says which stored contents the
// caller may name: one it may not is reported as not uploaded, exactly as a missing one, so a refusal
// does not tell that another tenant stored it.
void RequireBlobs(const BlobStore& blobs, const v1::Manifest& manifest, const std::string& what,
                  const std::function<bool(const std::string&)>& usable = {}) {
  int missing = 0;
  std::string first;
  for (const auto& file : manifest.files()) {
    const auto stored = usable && !usable(file.sha256()) ? std::nullopt : blobs.SizeOf(file.sha256());
    if (!stored) {
      if (missing++ == 0) first = file.path();
      continue;
    }
    // The stored content's size is the file's: a size declared smaller would be counted so against
    // the tenant's quota while the worker gets every byte.
    if (*stored != file.size()) {
      FailInvalid("file '" + file.path() + "' of the " + what + " is declared " +
                  std::to_string(file.size()) + " bytes, but its content (sha256 " + file.sha256() +
                  ") has " + std::to_string(*stored));
    }
  }
  if (missing > 0) {
    endorecon::Fail(ErrorCode::kFailedPrecondition, std::to_string(missing) + " file(s) of the " + what +
                                                        " are not uploaded yet, first '" + first +
                                                        "'; upload them first");
  }
}

// "cancelled by request", or "cancelled by it-ops (admin)" when the caller had a token.
std::string CancelledBy(const v1::Job& job) {
  return job.cancelled_by().empty() ? "cancelled by request" : "cancelled by " + job.cancelled_by();
}

// A job that did not succeed has nothing to send: its sends end SEND_FAILED saying why, so the job
// is settled (a watch ends, retention may expire it). They were left PENDING for good.
void SettleSends(v1::Job& job) {
  for (auto& send : *job.mutable_sends()) {
    if (!SendWaiting(send)) continue;
    send.set_state(v1::DicomSend::SEND_FAILED);
    send.set_next_attempt_unix_ms(0);
    send.set_error("not sent: the job ended " + v1::JobState_Name(job.state()) + " without results");
  }
}

// Keeps one send per destination, the first. A destination given twice (`--send-to orthanc --send-to
// orthanc`) made two sends, and the second stayed PENDING for good: the sender works on the first of
// a name, and the job could never be deleted (found 2026-12-07). Returns whether any was dropped.
bool DropDuplicateSends(v1::Job& job) {
  std::set<std::string> seen;
  auto* sends = job.mutable_sends();
  const int before = sends->size();
  sends->erase(
      std::remove_if(sends->begin(), sends->end(),
                     [&](const v1::DicomSend& send) { return !seen.insert(send.destination()).second; }),
      sends->end());
  return sends->size() != before;
}

// "no job 'ID'", with what an id looks like when `id` does not: a short or upper-case id ("f15961")
// read as a job that went away (found 2026-12-07).
[[noreturn]] void FailNoJob(const std::string& id) {
  const bool like_an_id = id.size() == 12 && id.find_first_not_of("0123456789abcdef") == std::string::npos;
  endorecon::Fail(
      ErrorCode::kNotFound,
      "no job '" + id + "'" +
          (like_an_id ? "" : " (a job id is 12 lower-case hexadecimal digits, as `endorecon list` shows)"));
}

}  // namespace

JobCoordinator::JobCoordinator(CoordinatorParts parts, int max_attempts, TenantQuotas quotas,
                               std::function<Clock::time_point()> clock)
    : parts_(parts), max_attempts_(max_attempts), quotas_(std::move(quotas)), clock_(std::move(clock)) {}

void JobCoordinator::KeepUploadsIn(const std::filesystem::path& file) {
  std::lock_guard lock(mutex_);
  uploads_.KeepIn(file);
  for (const auto& [tenant, digest] : uploads_.Proven()) holders_.Add(tenant, digest);
}

void JobCoordinator::KeepOrphansIn(const std::filesystem::path& file) {
  std::lock_guard lock(mutex_);
  orphans_.KeepIn(file);
}

void JobCoordinator::RequireHeld(const v1::Manifest& manifest, const std::string& what,
                                 const std::string& tenant, const std::string& who) {
  int unheld = 0;  // stored, but not the tenant's
  try {
    RequireBlobs(parts_.blobs, manifest, what, [&](const std::string& digest) {
      if (holders_.Holds(tenant, digest)) return true;
      if (parts_.blobs.Has(digest)) ++unheld;
      return false;
    });
  } catch (const Error& e) {
    // The caller is told "not uploaded yet", as for content never stored; the server's log says more,
    // for the IT staff. No file name: those may carry patient data.
    if (e.code() == ErrorCode::kFailedPrecondition && unheld > 0) {
      spdlog::warn(
          "{} named {} stored file(s) of the {} that tenant '{}' does not hold, without uploading "
          "them: refused as not uploaded (proof of possession). The endorecon client and worker "
          "upload what they name: from a client this is a request made by hand or with digests "
          "learned elsewhere; from a worker, results it uploaded before a server restart, which it "
          "sends again",
          who, unheld, what, tenant.empty() ? "-" : tenant);
    }
    throw;
  }
}

UploadOwner JobCoordinator::UploadOwnerOf(const std::string& tenant) {
  UploadOwner owner;
  owner.tenant = tenant;
  owner.unproven = [this, tenant](const v1::Manifest& manifest) {
    std::set<std::string> unproven;
    {
      std::lock_guard lock(mutex_);
      for (const auto& file : manifest.files()) {
        if (!holders_.Holds(tenant, file.sha256())) unproven.insert(file.sha256());
      }
    }
    // A stat a file: outside the lock (a new clip's files are all not held).
    std::erase_if(unproven, [this](const std::string& digest) { return !parts_.blobs.Has(digest); });
    return unproven;
  };
  owner.proven = [this, tenant](const std::string& digest) {
    std::lock_guard lock(mutex_);
    holders_.Add(tenant, digest);
    uploads_.NoteProven(tenant, digest);
  };
  owner.ended = [this] {
    std::lock_guard lock(mutex_);
    uploads_.Flush();
  };
  return owner;
}

UploadOwner JobCoordinator::ClientUploadOwner(const Principal& caller) {
  return UploadOwnerOf(caller.tenant);
}

UploadOwner JobCoordinator::WorkerUploadOwner(const std::optional<std::string>& served_tenant) {
  return served_tenant ? UploadOwnerOf(*served_tenant) : UploadOwner{};
}

void JobCoordinator::Recover() {
  std::lock_guard lock(mutex_);
  parts_.store.Scan([this](const StoredJob& stored) { holders_.AddJob(stored.job); });
  SettleLegacyUploads();
  const auto now = clock_();
  int queued = 0, running = 0;
  std::vector<std::string> retrieving, sending;
  for (const auto& stored : parts_.store.Unfinished()) {
    if (stored.job.state() == v1::QUEUED && Retrieving(stored.job)) {
      retrieving.push_back(stored.job.id());
    } else if (stored.job.state() == v1::QUEUED) {
      parts_.scheduler.Push(stored.job.id(), stored.job.priority(), stored.seq, stored.job.tenant());
      ++queued;
    } else {
      parts_.leases.Restore(stored.job.lease_id(), stored.job.id(), stored.job.worker_id(), now);
      parts_.workers.AddJob(stored.job.worker_id(), stored.job.id());
      ++running;
    }
    parts_.hub.PublishJob(stored.job);
  }
  for (std::int64_t before = 0;;) {
    auto page = parts_.store.List({v1::SUCCEEDED}, 500, before);
    for (auto& job : page.jobs) {
      if (DropDuplicateSends(job)) Save(job);  // stored by a server of before DropDuplicateSends
      if (SendsWaiting(job)) sending.push_back(job.id());
    }
    if (page.next_before_seq == 0) break;
    before = page.next_before_seq;
  }
  // Jobs that failed or were cancelled with sends still waiting, by a server of before SettleSends.
  for (std::int64_t before = 0;;) {
    auto page = parts_.store.List({v1::FAILED, v1::CANCELLED}, 500, before);
    for (auto& job : page.jobs) {
      if (!SendsWaiting(job)) continue;
      SettleSends(job);
      Save(job);
    }
    if (page.next_before_seq == 0) break;
    before = page.next_before_seq;
  }
  spdlog::info("recovered {} queued and {} running job(s), {} retrieval(s) and {} DICOM send(s) to resume",
               queued, running, retrieving.size(), sending.size());
  for (const auto& id : retrieving) {
    if (dicom_.retrieve) dicom_.retrieve(id);
  }
  for (const auto& id : sending) {
    if (dicom_.send) dicom_.send(id);
  }
}

void JobCoordinator::SetDicomHooks(DicomHooks hooks) { dicom_ = std::move(hooks); }

void JobCoordinator::SettleLegacyUploads() {
  // An upload noted by a server of before proof of possession (2026-12-06) went into the shared
  // partial <sha256>.part, and nothing says whose stream completed a content. One that only its tenant's
  // upload brings, and that no other tenant's job names, was sent by that tenant: its content is the
  // tenant's, and its partial becomes the tenant's to resume. The others are sent again (the re-test
  // of the upgrade found 247 MB of an upload not yet submitted sent again, its 12.6 MB partial left
  // behind, unlisted, until --orphan-hours).
  int taken = 0, partials = 0, left = 0;
  uploads_.SettleLegacy([&](const std::string& tenant, const std::string& digest) {
    if (uploads_.Noters(digest) != 1 || holders_.HeldByAnother(tenant, digest)) {
      ++left;
      return false;
    }
    if (parts_.blobs.Has(digest)) {
      holders_.Add(tenant, digest);
      ++taken;
      return true;
    }
    if (parts_.blobs.AdoptPartial(digest, tenant)) ++partials;  // none for the admins' (theirs already)
    return false;
  });
  if (taken + partials + left > 0) {
    spdlog::info(
        "uploads not yet submitted from before proof of possession: {} complete file(s) taken as their "
        "tenant's, {} partial(s) made their tenant's to resume, {} to be sent again (another tenant's "
        "upload or job brings the same content)",
        taken, partials, left);
  }
}

void JobCoordinator::RemoveBlob(const std::string& digest) {
  parts_.blobs.Remove(digest);
  holders_.Forget(digest);
}

void JobCoordinator::RemoveFile(const BlobStore::StoredFile& file) {
  if (!file.partial) return RemoveBlob(file.sha256);
  parts_.blobs.Remove(file);
}

StoredJob JobCoordinator::Load(const std::string& id) {
  auto stored = parts_.store.Get(id);
  if (!stored) FailNoJob(id);
  return *stored;
}

StoredJob JobCoordinator::LoadVisible(const std::string& id, const Principal& caller) {
  auto stored = parts_.store.Get(id);
  if (!stored || (!caller.SeesAllTenants() && stored->job.tenant() != caller.tenant)) FailNoJob(id);
  return *stored;
}

StoredJob JobCoordinator::LoadLeased(const std::string& lease_id) {
  const auto lease = parts_.leases.Find(lease_id);
  if (!lease) {
    endorecon::Fail(ErrorCode::kFailedPrecondition,
                    "lease '" + lease_id +
                        "' is not held: it expired, or its job was cancelled or handed to another worker");
  }
  parts_.workers.Touch(lease->worker_id);
  return Load(lease->job_id);
}

void JobCoordinator::Save(const v1::Job& job) {
  parts_.store.Update(job);
  parts_.hub.PublishJob(job);
}

void JobCoordinator::Finish(v1::Job& job, v1::JobState state, const std::string& error) {
  if (!job.lease_id().empty()) parts_.leases.Release(job.lease_id());
  if (!job.worker_id().empty()) parts_.workers.RemoveJob(job.worker_id(), job.id());
  job.set_state(state);
  job.set_error(error);
  job.set_finished_unix_ms(NowUnixMs());
  job.clear_lease_id();
  if (state != v1::SUCCEEDED) SettleSends(job);
  Save(job);
  const double run_seconds =
      job.started_unix_ms() > 0 ? static_cast<double>(job.finished_unix_ms() - job.started_unix_ms()) / 1000.0
                                : -1.0;
  parts_.metrics.JobFinished(state, run_seconds);
  spdlog::info("job {} {}{}{}", job.id(), v1::JobState_Name(state), error.empty() ? "" : ": ", error);
}

void JobCoordinator::Requeue(StoredJob& stored, bool count_attempt, const std::string& reason) {
  auto& job = stored.job;
  if (count_attempt) job.set_attempts(job.attempts() + 1);
  if (job.attempts() >= job.max_attempts()) {
    Finish(job, v1::FAILED,
           "gave up after " + std::to_string(job.attempts()) + " attempt(s) (max_attempts); last: " + reason);
    return;
  }
  parts_.leases.Release(job.lease_id());
  parts_.workers.RemoveJob(job.worker_id(), job.id());
  job.set_state(v1::QUEUED);
  job.set_error(reason);
  job.clear_lease_id();
  job.clear_worker_id();
  Save(job);
  parts_.scheduler.Push(job.id(), job.priority(), stored.seq, job.tenant());
  spdlog::info("job {} requeued (attempts {}/{}): {}", job.id(), job.attempts(), job.max_attempts(), reason);
}

void JobCoordinator::CheckQuotas(const std::string& tenant, const v1::Manifest& adding, bool adds_job,
                                 std::int64_t pending) {
  quotas_.Refresh();  // an admin's change to the --quotas file holds from the next check
  const auto quota = quotas_.For(tenant);
  const bool counts_jobs = adds_job && quota.max_jobs > 0;
  if (!counts_jobs && quota.max_bytes == 0) return;
  // A tenant's usage is a scan of its jobs: counted only when a quota needs it, and once.
  const auto usage = parts_.store.UsageOf(tenant);
  // Admins and callers without a token have the empty tenant, which listings show as "-".
  const std::string named = "tenant '" + (tenant.empty() ? std::string("-") : tenant) + "'";
  if (counts_jobs && usage.active_jobs >= quota.max_jobs) {
    endorecon::Fail(ErrorCode::kResourceExhausted,
                    named + " has " + std::to_string(usage.active_jobs) +
                        " job(s) queued or running, its quota max_jobs is " + std::to_string(quota.max_jobs) +
                        "; submit again when one has finished");
  }
  const std::int64_t bytes = TotalBytes(adding);
  if (quota.max_bytes > 0 && usage.bytes + pending + bytes > quota.max_bytes) {
    const std::string uploads =
        pending == 0 ? ""
                     : ", " + std::to_string(pending) + " in uploads not yet submitted (the last at " +
                           UtcText(uploads_.LastNotedUnixMs(tenant)) +
                           "; they count until submitted or dropped, or until the server's --orphan-hours "
                           "after their last upload),";
    endorecon::Fail(
        ErrorCode::kResourceExhausted,
        named + " keeps " + std::to_string(usage.bytes) + " bytes in its jobs" + uploads + " and this adds " +
            std::to_string(bytes) + LargestFileNote(adding) + ": over its quota max_bytes of " +
            std::to_string(quota.max_bytes) +
            " bytes; delete the files of a finished job of it (`endorecon delete JOB`; a queued or "
            "running one: cancel it first)" +
            (pending == 0 ? ""
                          : ", or finish an upload not yet submitted (`endorecon submit` of the same clip "
                            "resumes and submits it), or give those up (`endorecon uploads --drop`)"));
  }
}

void JobCoordinator::CheckUploadQuota(const v1::Manifest& manifest, const Principal& caller) {
  // Both quotas before any byte: an upload the submit would refuse is not sent.
  std::lock_guard lock(mutex_);
  CheckQuotas(caller.tenant, manifest, true);
}

void JobCoordinator::AdmitUpload(const v1::Manifest& manifest, const Principal& caller) {
  std::lock_guard lock(mutex_);
  CheckQuotas(caller.tenant, manifest, true, uploads_.PendingBytes(caller.tenant, manifest));
  // Noted with or without a byte quota: `endorecon uploads` lists and drops them either way.
  // A stored content the tenant does not hold is uploaded again (BlobHolders): it is this upload's too.
  uploads_.Note(
      caller.tenant, manifest,
      [&](const std::string& digest) {
        return parts_.blobs.Has(digest) && holders_.Holds(caller.tenant, digest);
      },
      UploadLedger::Time::clock::now());
}

std::int64_t JobCoordinator::PendingUploadBytes() {
  std::lock_guard lock(mutex_);
  std::int64_t bytes = 0;
  for (const auto& [tenant, pending] : uploads_.Tenants()) bytes += pending.bytes;
  return bytes;
}

v1::UploadsResponse JobCoordinator::Uploads(const v1::UploadsRequest& request, const Principal& caller) {
  std::optional<std::string> tenant;  // nullopt: every tenant's
  if (caller.SeesAllTenants()) {
    if (!request.tenant().empty()) tenant = request.tenant() == "-" ? "" : request.tenant();
    if (tenant && !tenant->empty()) ValidateTenant(*tenant);  // a typo, or text for the server's log
  } else {
    if (!request.tenant().empty() && request.tenant() != caller.tenant) {
      endorecon::Fail(
          ErrorCode::kPermissionDenied,
          "a client token acts on its own tenant's uploads only (tenant '" + caller.tenant + "')");
    }
    tenant = caller.tenant;
  }
  // A server without tokens has one tenant, its callers' own: a drop needs no name there (it asked for
  // `--tenant -` on the demo server).
  if (request.drop() && !tenant && caller.anonymous) tenant = "";
  if (request.drop() && !tenant) {
    FailInvalid("name the tenant whose uploads not yet submitted to drop (--tenant; '-' for that of admins)");
  }
  // The store's files are a folder walk: listed outside the lock, as retention's are (a file stored
  // after the listing is not in it, so it cannot be taken for one no job holds).
  const auto files = request.drop() ? parts_.blobs.Files() : std::vector<BlobStore::StoredFile>{};
  std::lock_guard lock(mutex_);
  v1::UploadsResponse response;
  for (const auto& [name, pending] : uploads_.Tenants()) {
    if (tenant && name != *tenant) continue;
    auto* listed = response.add_tenants();
    listed->set_tenant(name);
    listed->set_files(pending.files);
    listed->set_bytes(pending.bytes);
    listed->set_last_unix_ms(pending.last_unix_ms);
    // What arrived: a stat a file (a listing is an admin's or a user's question, not a hot path).
    std::int64_t arrived = 0;
    for (const auto& [digest, bytes] : uploads_.Files(name)) {
      v1::FileEntry entry;
      entry.set_sha256(digest);
      entry.set_size(bytes);
      arrived += holders_.Holds(name, digest) && parts_.blobs.Has(digest)
                     ? bytes
                     : parts_.blobs.PartialBytes(entry, name);
    }
    listed->set_arrived_bytes(arrived);
  }
  if (!request.drop()) return response;
  const auto digests = uploads_.Drop(*tenant);
  std::set<std::string> dropped;
  for (const auto& digest : digests) {
    if (!uploads_.Holds(digest)) dropped.insert(digest);  // another tenant's upload brings it too
  }
  // The tenant's own partials go whoever else uploads the content; a blob only when no other
  // tenant's upload brings it.
  const std::set<std::string> own(digests.begin(), digests.end());
  std::vector<BlobStore::StoredFile> candidates;
  for (const auto& file : files) {
    if (file.partial ? file.owner == *tenant && own.count(file.sha256) : dropped.count(file.sha256) > 0)
      candidates.push_back(file);
  }
  // Of those, the files no job references (PlanExpiry's orphans, with no job expiring).
  const auto plan = PlanExpiry(
      parts_.store, parts_.blobs, [](const v1::Job&) { return false; }, candidates);
  for (const auto& file : plan.orphans) RemoveFile(file);
  // The tenant gives its uploads up: it holds (BlobHolders) only what its jobs name. Without this a
  // dropped upload's content could still be submitted while another tenant kept it, and no more
  // after a restart (found 2026-12-06).
  std::set<std::string> named;
  parts_.store.Scan([&](const StoredJob& stored) {
    if (stored.job.tenant() == *tenant && stored.job.expired_unix_ms() == 0) AddJobFiles(stored.job, named);
  });
  for (const auto& digest : digests) {
    if (!named.count(digest)) holders_.Remove(*tenant, digest);
  }
  // What the drop deleted tells which of the files another tenant or its job holds: an admin's only.
  if (caller.SeesAllTenants()) {
    response.set_deleted_files(static_cast<std::int64_t>(plan.orphans.size()));
    response.set_deleted_bytes(plan.orphan_bytes);
  }
  spdlog::info("uploads not yet submitted of tenant '{}' dropped by {}: {} file(s), {} deleted ({} bytes)",
               tenant->empty() ? "-" : *tenant, caller.name, digests.size(), plan.orphans.size(),
               plan.orphan_bytes);
  return response;
}

void JobCoordinator::CheckRetrievalQuota(const std::string& id, const v1::Manifest& recording) {
  std::lock_guard lock(mutex_);
  CheckQuotas(Load(id).job.tenant(), recording, false);
}

v1::Job JobCoordinator::Submit(const v1::SubmitRequest& request, const Principal& caller) {
  const bool from_pacs = !request.pacs().pacs().empty();
  if (from_pacs) {
    if (dicom_.pacs == nullptr) FailInvalid("pacs: this server has no PACS configured (--pacs)");
    dicom_.pacs->Find(request.pacs().pacs());
    dicom::CheckUid(request.pacs().study_uid(), "pacs.study_uid");
    if (!request.pacs().series_uid().empty()) dicom::CheckUid(request.pacs().series_uid(), "pacs.series_uid");
    if (request.clip().files_size() > 0) FailInvalid("a job names either a clip or a PACS study, not both");
  } else {
    ValidateManifest(request.clip(), request.validate_only() && IsSizesOnly(request.clip()));
  }
  ValidateJobName(request.name());
  ValidatePriority(request.priority());
  ValidateOptions(request.options());
  if (request.has_prepare()) CheckPrepareOptions(request.prepare(), request.clip());
  ValidateRecording(request.recording());
  if (!request.dicom().study_uid().empty()) dicom::CheckUid(request.dicom().study_uid(), "dicom.study_uid");
  dicom::CheckPatientId(request.dicom().patient_id(), "dicom.patient_id");
  dicom::CheckPatientName(request.dicom().patient_name(), "dicom.patient_name");
  dicom::CheckStudyJoin(request.dicom().patient_id(), request.dicom().study_uid());
  for (const auto& name : request.send_to()) {
    if (dicom_.pacs == nullptr) FailInvalid("send_to: this server has no PACS configured (--pacs)");
    dicom_.pacs->Find(name);
  }
  v1::Job job;
  job.set_id(RandomId(6));
  job.set_name(request.name());
  job.set_state(v1::QUEUED);
  job.set_priority(request.priority());
  *job.mutable_options() = request.options();
  *job.mutable_clip() = request.clip();
  if (request.has_prepare()) *job.mutable_prepare() = request.prepare();
  *job.mutable_recording() = request.recording();
  *job.mutable_dicom() = request.dicom();
  job.mutable_dicom()->set_uid_root(dicom_.uid_root);
  if (request.send_to_size() > 0) job.mutable_dicom()->set_enabled(true);
  for (const auto& name : request.send_to()) {
    auto* send = job.add_sends();
    send->set_destination(name);
    send->set_state(v1::DicomSend::PENDING);
  }
  DropDuplicateSends(job);
  if (from_pacs) {
    *job.mutable_retrieval()->mutable_source() = request.pacs();
    job.mutable_retrieval()->set_state(v1::Retrieval::RETRIEVING);
  }
  job.set_created_unix_ms(NowUnixMs());
  job.set_max_attempts(max_attempts_);
  job.set_tenant(caller.tenant);
  if (!caller.anonymous) job.set_submitted_by(caller.name);
  if (request.validate_only()) {
    CheckUploadQuota(request.clip(), caller);
    job.clear_id();
    return job;
  }
  // A recording's options against its files' headers, before the queue; outside the lock (a folder
  // of many files takes a while to read).
  if (!from_pacs && !request.has_prepare()) CheckRecording(request.clip(), request.recording(), parts_.blobs);
  // Under the lock, so retention cannot delete a blob between this check and the insert, and two
  // submits cannot both take a tenant's last job slot.
  Locked([&] {
    if (!from_pacs) {
      RequireHeld(request.clip(), request.has_prepare() ? "recording" : "clip", caller.tenant,
                  "client '" + caller.name + "'");
    }
    CheckQuotas(caller.tenant, request.clip(), true, uploads_.PendingBytes(caller.tenant, request.clip()));
    const auto seq = parts_.store.Insert(job);
    holders_.AddJob(job);
    uploads_.Submitted(caller.tenant, request.clip());
    parts_.hub.PublishJob(job);
    if (!from_pacs) parts_.scheduler.Push(job.id(), job.priority(), seq, job.tenant());
    parts_.metrics.JobSubmitted();
  });
  if (from_pacs) {
    spdlog::info("job {} submitted: its recording is retrieved from PACS {}", job.id(),
                 request.pacs().pacs());
    dicom_.retrieve(job.id());
  } else {
    spdlog::info("job {} submitted: {} file(s), {} bytes, priority {}", job.id(), job.clip().files_size(),
                 TotalBytes(job.clip()), job.priority());
  }
  return job;
}

v1::Job JobCoordinator::Get(const std::string& id, const Principal& caller) {
  return LoadVisible(id, caller).job;
}

JobStore::Page JobCoordinator::List(const std::vector<v1::JobState>& states, int limit,
                                    const std::string& after_job, const Principal& caller) {
  std::int64_t before_seq = 0;
  if (!after_job.empty()) {
    try {
      before_seq = LoadVisible(after_job, caller).seq;
    } catch (const Error&) {
      FailInvalid("page_token '" + after_job + "' is not one this server returned to this caller");
    }
  }
  return parts_.store.List(
      states, limit, before_seq,
      caller.SeesAllTenants() ? std::nullopt : std::optional<std::string>(caller.tenant));
}

v1::Job JobCoordinator::Cancel(const std::string& id, const Principal& caller) {
  return Locked([&] {
    auto job = LoadVisible(id, caller).job;
    if (Terminal(job.state())) {
      endorecon::Fail(ErrorCode::kFailedPrecondition,
                      "job " + id + " is already " + v1::JobState_Name(job.state()));
    }
    if (!caller.anonymous)
      job.set_cancelled_by(caller.name + (caller.role == Role::kAdmin ? " (admin)" : ""));
    if (job.state() == v1::QUEUED) {
      parts_.scheduler.Remove(id);
      Finish(job, v1::CANCELLED, CancelledBy(job) + " while queued");
    } else {
      job.set_cancel_requested(true);
      Save(job);
    }
    return job;
  });
}

v1::Job JobCoordinator::Delete(const std::string& id, const Principal& caller) {
  RetentionPlan plan;
  bool deleted_before = false;
  const v1::Job job = Locked([&] {
    auto job = LoadVisible(id, caller).job;
    deleted_before = job.expired_unix_ms() > 0;  // by an earlier delete or by retention: asking again is
    if (deleted_before) return job;              // no error, and the job says when
    if (!Settled(job)) {
      endorecon::Fail(ErrorCode::kFailedPrecondition,
                      "job " + id + " is " + v1::JobState_Name(job.state()) +
                          (Terminal(job.state()) ? " with DICOM sends to go: delete it once they are done"
                                                 : ": cancel it first, or delete it once it has finished"));
    }
    plan = PlanExpiry(
        parts_.store, parts_.blobs, [&](const v1::Job& one) { return one.id() == id; }, {},
        [&](const std::string& digest) { return uploads_.Holds(digest); });
    for (const auto& digest : plan.blobs) RemoveBlob(digest);  // files first, as retention
    job.set_expired_unix_ms(NowUnixMs());
    Save(job);
    return job;
  });
  if (deleted_before) return job;
  parts_.metrics.JobsExpired(1);
  spdlog::info(
      "job {}: files deleted by request of {} ({} blob(s), {} bytes; kept {} shared with other jobs, {} "
      "that uploads not yet submitted bring)",
      id, caller.name, plan.blobs.size(), plan.bytes, plan.kept_shared, plan.kept_uploading);
  return job;
}

std::optional<JobCoordinator::Granted> JobCoordinator::Lease(const std::string& worker_id,
                                                             Clock::time_point deadline,
                                                             const std::optional<std::string>& tenant,
                                                             const std::function<bool()>& cancelled,
                                                             const LeaseToken& token) {
  parts_.workers.Touch(worker_id);
  // The wait is cut into slices, and a call its worker cancelled (a worker stopping cancels its lease
  // calls, then leaves) ends at the next: it took the next job 4 s after its worker had stopped, and
  // listed the worker alive again (found 2026-12-06).
  const auto gone = [&] { return Clock::now() >= deadline || (cancelled && cancelled()); };
  constexpr auto kSlice = std::chrono::milliseconds(500);
  while (true) {
    if (cancelled && cancelled()) return std::nullopt;
    // A draining worker is given nothing: its call waits out its deadline (as an empty queue's would,
    // so it does not poll in a loop), or until the drain is undone.
    while (parts_.workers.Draining(worker_id)) {
      if (gone()) return std::nullopt;
      std::this_thread::sleep_until(std::min(deadline, Clock::now() + std::chrono::milliseconds(200)));
    }
    const auto next = parts_.scheduler.PopWait(std::min(deadline, Clock::now() + kSlice), tenant);
    if (!next) {
      if (gone()) return std::nullopt;
      continue;
    }
    auto granted = Locked([&]() -> std::optional<Granted> {
      auto stored = parts_.store.Get(*next);
      if (!stored || stored->job.state() != v1::QUEUED) return std::nullopt;
      auto& job = stored->job;
      // Drained or cancelled while this call waited for a job: the job goes back for another worker.
      if (parts_.workers.Draining(worker_id) || (cancelled && cancelled())) {
        parts_.scheduler.Push(job.id(), job.priority(), stored->seq, job.tenant());
        return std::nullopt;
      }
      const auto lease = parts_.leases.Grant(job.id(), worker_id, clock_(), token);
      job.set_state(v1::RUNNING);
      // The last run's progress is not this run's: `status` showed "evaluating the results: frame 2/6"
      // while the new worker loaded the clip (found 2026-12-07).
      job.clear_progress();
      job.set_lease_id(lease.id);
      job.set_worker_id(worker_id);
      job.set_started_unix_ms(NowUnixMs());
      if (job.first_started_unix_ms() == 0) job.set_first_started_unix_ms(job.started_unix_ms());
      Save(job);
      parts_.workers.AddJob(worker_id, job.id());
      parts_.metrics.LeaseGranted();
      return Granted{job, lease.id, job.attempts() + 1};
    });
    if (granted) {
      spdlog::info("job {} leased to {} (attempt {})", granted->job.id(), worker_id, granted->attempt);
      return granted;
    }
  }
}

v1::ProgressReply::Action JobCoordinator::Report(const v1::ProgressUpdate& update, const LeaseToken& token,
                                                 std::string* job_id, bool* register_again,
                                                 const std::optional<std::string>& served_tenant) {
  return Locked([&] { return ReportLocked(update, token, job_id, register_again, served_tenant); });
}

v1::ProgressReply::Action JobCoordinator::ReportLocked(const v1::ProgressUpdate& update,
                                                       const LeaseToken& token, std::string* job_id,
                                                       bool* register_again,
                                                       const std::optional<std::string>& served_tenant) {
  const auto lease = parts_.leases.Renew(update.lease_id(), clock_(), token);
  if (!lease) return v1::ProgressReply::STOP_LEASE_LOST;
  if (job_id) *job_id = lease->job_id;
  if (register_again) *register_again = !parts_.workers.Registered(lease->worker_id);
  parts_.workers.Touch(lease->worker_id);
  auto stored = Load(lease->job_id);
  auto& job = stored.job;
  if (job.cancel_requested()) {
    Finish(job, v1::CANCELLED, CancelledBy(job) + " while running on " + job.worker_id());
    return v1::ProgressReply::STOP_CANCELLED;
  }
  bool changed = false;
  // A worker of one tenant names only content that tenant holds: a checkpoint is downloaded again by
  // the job's next worker (GetBlobs).
  if (update.has_checkpoint() && parts_.blobs.Has(update.checkpoint().sha256())) {
    if (!served_tenant || holders_.Holds(job.tenant(), update.checkpoint().sha256())) {
      *job.mutable_checkpoint() = update.checkpoint();
      holders_.Add(job.tenant(), update.checkpoint().sha256());
      changed = true;
    } else {
      spdlog::warn(
          "job {}: the checkpoint worker {} names is no content tenant '{}' holds (not uploaded by it, "
          "or uploaded before a server restart): left out",
          job.id(), job.worker_id(), job.tenant());
    }
  }
  if (update.has_progress()) {
    *job.mutable_progress() = update.progress();
    parts_.store.Update(job);
    parts_.hub.PublishProgress(job.id(), update.progress());
  } else if (changed) {
    parts_.store.Update(job);
  }
  if (update.has_preview()) {
    // The kind names the client's file of it (job_watcher.cc): only the kinds a worker makes pass.
    const std::string& kind = update.preview().kind();
    if (kind == "rgb" || kind == "depth" || kind == "uncertainty" || kind == "prepare") {
      parts_.hub.PublishPreview(job.id(), update.preview());
    } else {
      spdlog::warn("job {}: a preview of unknown kind '{}' from worker {} dropped", job.id(),
                   kind.substr(0, 64), job.worker_id());
    }
  }
  return v1::ProgressReply::CONTINUE;
}

v1::Job JobCoordinator::Complete(const v1::CompleteRequest& request,
                                 const std::optional<std::string>& served_tenant, std::string* job_id) {
  ValidateManifest(request.result());
  auto job = Locked([&] {
    auto job = LoadLeased(request.lease_id()).job;
    if (job_id) *job_id = job.id();
    // A worker of one tenant names only content that tenant holds (or that it uploaded itself): its
    // results are downloaded by the tenant's clients and sent to its PACS.
    if (served_tenant) {
      RequireHeld(request.result(), "result", job.tenant(), "worker " + job.worker_id());
    } else {
      RequireBlobs(parts_.blobs, request.result(), "result");
    }
    *job.mutable_result() = request.result();
    holders_.AddFiles(job.tenant(), job.result());
    job.set_summary_json(request.summary_json());
    Finish(job, v1::SUCCEEDED, "");
    return job;
  });
  if (SendsWaiting(job) && dicom_.send) dicom_.send(job.id());
  return job;
}

v1::Job JobCoordinator::Fail(const v1::FailRequest& request) {
  return Locked([&] {
    auto stored = LoadLeased(request.lease_id());
    auto& job = stored.job;
    const std::string reason = request.reason().empty() ? "the worker gave no reason" : request.reason();
    if (job.cancel_requested()) {
      Finish(job, v1::CANCELLED, CancelledBy(job) + " while running on " + job.worker_id());
    } else if (request.retry()) {
      Requeue(stored, !request.release(), "worker " + job.worker_id() + ": " + reason);
    } else {
      Finish(job, v1::FAILED, "worker " + job.worker_id() + ": " + reason);
    }
    return job;
  });
}

v1::Job JobCoordinator::CheckLease(const std::string& lease_id) {
  std::lock_guard lock(mutex_);
  return LoadLeased(lease_id).job;
}

RetentionPlan JobCoordinator::ExpireFinishedBefore(std::int64_t cutoff_unix_ms,
                                                   const OrphanCutoff& orphan_cutoff) {
  // Every file, not only old ones: the watch notes when each is first found no job's. A folder walk:
  // outside the lock (PlanExpiry).
  const bool orphans_go = orphan_cutoff.written_before != std::filesystem::file_time_type::min();
  const auto files = orphans_go ? parts_.blobs.Files() : std::vector<BlobStore::StoredFile>{};
  auto plan = Locked([&] {
    // Uploads last noted before the cutoff are given up first, and their files with the plan's.
    uploads_.ForgetBefore(orphan_cutoff.written_before);
    auto plan = PlanRetention(parts_.store, parts_.blobs, cutoff_unix_ms, files,
                              [&](const std::string& digest) { return uploads_.Holds(digest); });
    if (orphans_go) orphans_.Sift(plan, orphan_cutoff, NowUnixMs());
    // Files first: a crash in between leaves jobs that the next run expires (their blobs already
    // gone), never a job marked expired whose files are still kept.
    for (const auto& digest : plan.blobs) RemoveBlob(digest);
    for (const auto& file : plan.orphans) RemoveFile(file);
    const auto now = NowUnixMs();
    for (auto& job : plan.jobs) {
      job.set_expired_unix_ms(now);
      Save(job);
    }
    return plan;
  });
  parts_.metrics.JobsExpired(plan.jobs.size());
  if (!plan.jobs.empty()) {
    spdlog::info(
        "retention: expired {} job(s), deleted {} blob(s) ({} bytes), kept {} shared with other jobs, {} "
        "that uploads not yet submitted bring",
        plan.jobs.size(), plan.blobs.size(), plan.bytes, plan.kept_shared, plan.kept_uploading);
  }
  if (!plan.orphans.empty()) {
    spdlog::info(
        "retention: deleted {} file(s) ({} bytes) no job references (earlier checkpoints, uploads "
        "never submitted, partial uploads)",
        plan.orphans.size(), plan.orphan_bytes);
  }
  return plan;
}

void JobCoordinator::ExpireLeases(Clock::time_point now, const std::string& server_refusing) {
  const auto expired = parts_.leases.TakeExpired(now);
  if (expired.empty()) return;
  // Why each lease's worker may have been refused, asked of the token store outside the lock: a token
  // revoked mid-job made a reason of "stopped reporting" (found 2026-12-06).
  std::vector<std::int64_t> revoked_at(expired.size(), 0);
  for (std::size_t i = 0; i < expired.size() && token_revoked_at_; ++i)
    revoked_at[i] = token_revoked_at_(expired[i].token.name);
  Locked([&] {
    for (std::size_t i = 0; i < expired.size(); ++i) {
      const auto& lease = expired[i];
      auto stored = parts_.store.Get(lease.job_id);
      if (!stored || stored->job.state() != v1::RUNNING || stored->job.lease_id() != lease.id) continue;
      parts_.metrics.LeaseExpired();
      const auto& token = lease.token;
      const bool token_lapsed = token.expires_unix_ms > 0 && token.expires_unix_ms <= NowUnixMs();
      const std::string refused = ", so its calls were refused and its lease expired";
      // The server's own token store not opening refused every worker's calls (found 2026-12-07).
      const bool server_fault = !server_refusing.empty();
      // A worker stopping while the server was down (a batch allocation's time limit) could not hand
      // its job back, and the lease the restarted server re-granted then expired: it cost an attempt,
      // and a few outages failed jobs outright (found 2026-12-07).
      const bool server_was_down = lease.restored;
      const std::string reason =
          "worker " + lease.worker_id +
          (server_fault ? "'s calls were refused because the server's token store does not open (" +
                              server_refusing + "), so its lease expired (not counted as an attempt)"
           : server_was_down
               ? " did not call after the server restarted (it may have stopped, handing the job back, while "
                 "the server was down), so its lease expired (not counted as an attempt)"
           : token_lapsed
               ? "'s token '" + token.name + "' expired at " + UtcText(token.expires_unix_ms) + refused +
                     " (not counted as an attempt; renew worker tokens before they expire)"
           : revoked_at[i] > 0
               ? "'s token '" + token.name + "' was revoked at " + UtcText(revoked_at[i]) + refused
               : " stopped reporting; its lease expired");
      if (stored->job.cancel_requested()) {
        Finish(stored->job, v1::CANCELLED, CancelledBy(stored->job) + "; " + reason);
      } else {
        Requeue(*stored, !token_lapsed && !server_fault && !server_was_down, reason);
      }
    }
  });
}

v1::Job JobCoordinator::RequestSend(const std::string& id, const std::string& destination,
                                    const Principal& caller) {
  v1::Job job;
  {
    std::lock_guard lock(mutex_);
    // The job first: whether a PACS exists must not tell apart another tenant's job from none.
    job = LoadVisible(id, caller).job;
    if (dicom_.pacs == nullptr) FailInvalid("this server has no PACS configured (--pacs)");
    dicom_.pacs->Find(destination);
    if (job.state() != v1::SUCCEEDED) {
      endorecon::Fail(ErrorCode::kFailedPrecondition, NoResultsYet(job, "sent"));
    }
    if (job.expired_unix_ms() > 0) {
      endorecon::Fail(
          ErrorCode::kFailedPrecondition,
          "job " + id + " expired: its results were deleted (retention, or a delete), DICOM included");
    }
    const bool has_dicom =
        std::any_of(job.result().files().begin(), job.result().files().end(),
                    [](const v1::FileEntry& f) { return f.path().rfind("dicom/", 0) == 0; });
    if (!has_dicom) {
      endorecon::Fail(ErrorCode::kFailedPrecondition,
                      "job " + id + " has no DICOM results (submit a DICOM recording, or pass --dicom)");
    }
    v1::DicomSend* send = nullptr;
    for (auto& existing : *job.mutable_sends()) {
      if (existing.destination() == destination) send = &existing;
    }
    if (send == nullptr) {
      send = job.add_sends();
      send->set_destination(destination);
    } else if (SendWaiting(*send)) {
      return job;
    }
    if (send->state() == v1::DicomSend::SENT) {
      send->clear_sent_paths();
      send->set_sent(0);
    }
    send->set_state(v1::DicomSend::PENDING);
    send->set_attempts(0);
    send->set_next_attempt_unix_ms(0);
    Save(job);
  }
  parts_.store.Flush();
  spdlog::info("job {}: DICOM results to be sent to {}", id, destination);
  if (dicom_.send) dicom_.send(id);
  return job;
}

v1::Job JobCoordinator::Update(const std::string& id, const std::function<void(v1::Job&)>& change) {
  return Locked([&] {
    auto job = Load(id).job;
    change(job);
    Save(job);
    return job;
  });
}

void JobCoordinator::RetrievalDone(const std::string& id, const v1::Manifest& clip) {
  // Checked before the queue as a submitted recording is (outside the lock): a window past its end
  // fails the job now, not after its wait for a worker.
  std::string refused;
  try {
    CheckRecording(clip, Locked([&] { return Load(id).job.recording(); }), parts_.blobs);
  } catch (const Error& e) {
    refused = e.what();
  }
  Locked([&] {
    auto stored = Load(id);
    auto& job = stored.job;
    if (job.state() != v1::QUEUED) return;  // cancelled meanwhile
    CheckQuotas(job.tenant(), clip, false);
    RequireBlobs(parts_.blobs, clip, "retrieved recording");  // retention may share and delete blobs
    *job.mutable_clip() = clip;
    holders_.AddFiles(job.tenant(), clip);
    job.mutable_retrieval()->set_state(v1::Retrieval::RETRIEVED);
    if (!refused.empty()) {
      Finish(job, v1::FAILED,
             "the recording retrieved from PACS " + job.retrieval().source().pacs() + ": " + refused);
      return;
    }
    Save(job);
    parts_.scheduler.Push(job.id(), job.priority(), stored.seq, job.tenant());
    spdlog::info("job {}: recording retrieved ({} file(s), {} bytes); queued", id, clip.files_size(),
                 TotalBytes(clip));
  });
}

void JobCoordinator::RetrievalFailed(const std::string& id, const std::string& reason) {
  Locked([&] {
    auto job = Load(id).job;
    if (job.state() != v1::QUEUED) return;
    job.mutable_retrieval()->set_state(v1::Retrieval::RETRIEVAL_FAILED);
    job.mutable_retrieval()->set_error(reason);
    Finish(job, v1::FAILED, "retrieval from PACS " + job.retrieval().source().pacs() + " failed: " + reason);
  });
}

}  // namespace endorecon::server
