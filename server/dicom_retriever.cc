#include "server/dicom_retriever.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <fstream>
#include <functional>
#include <optional>

#include "common/dicom/retrieve_scu.h"
#include "common/error.h"
#include "common/safe_path.h"
#include "common/sha256.h"

namespace endorecon::server {
namespace fs = std::filesystem;

DicomRetriever::DicomRetriever(JobCoordinator& coordinator, BlobStore& blobs, const PacsDirectory& pacs,
                               const DicomSettings& settings, Metrics& metrics, fs::path work_dir,
                               const dicom::StorageScp* scp, PacsAudit audit)
    : coordinator_(coordinator),
      blobs_(blobs),
      pacs_(pacs),
      settings_(settings),
      metrics_(metrics),
      work_dir_(std::move(work_dir)),
      scp_(scp),
      audit_(std::move(audit)),
      due_([this](const std::string& job_id) {
        try {
          Run(job_id);
        } catch (const std::exception& e) {
          spdlog::error("job {}: retrieval: {}", job_id, e.what());
        }
      }) {}

// The job is read when its turn comes (Retrieve may be called under the coordinator's lock): Run
// puts it back when its next attempt is not due yet.
void DicomRetriever::Retrieve(const std::string& job_id) { due_.Schedule(job_id, 0); }

void DicomRetriever::Received(const std::string& study_uid, std::int64_t bytes) {
  std::string job;
  int instances = 0;
  std::int64_t total = 0;
  {
    std::lock_guard lock(mutex_);
    if (study_uid != moving_study_ || moving_job_.empty()) return;
    job = moving_job_;
    instances = ++moved_instances_;
    total = moved_bytes_ += bytes;
  }
  Progress(job, instances, total);
}

bool DicomRetriever::Awaits(const std::string& study_uid) const {
  std::lock_guard lock(mutex_);
  return !moving_job_.empty() && study_uid == moving_study_;
}

void DicomRetriever::Progress(const std::string& job_id, int instances, std::int64_t bytes) {
  coordinator_.Update(job_id, [&](v1::Job& job) {
    metrics_.RetrievalBytes(bytes - job.retrieval().bytes());
    job.mutable_retrieval()->set_instances(instances);
    job.mutable_retrieval()->set_bytes(bytes);
  });
}

std::vector<std::string> DicomRetriever::RecordingSeries(const std::string& job_id,
                                                         const dicom::RetrieveRequest& request) {
  dicom::StudyContents contents;
  try {
    contents = dicom::FindStudyContents(request);
  } catch (const Error& e) {
    if (e.code() == ErrorCode::kUnavailable) throw;  // no answer: the attempt waits for the PACS
    spdlog::warn("job {}: cannot list the study's instances ({}); retrieving the whole study", job_id,
                 e.what());
    return {};
  }
  // C-FIND found nothing: no such study there. C-GET and C-MOVE were tried anyway, and their refusals
  // read as a PACS that would not send (found 2026-12-05). The UID is not repeated: it leads to a
  // patient, and the logs hold none.
  if (contents.recording_series.empty() && contents.other_classes.empty()) {
    Fail(ErrorCode::kNotFound, "PACS " + request.peer.ae_title +
                                   " holds no such study (C-FIND found no instance of it): check the Study "
                                   "Instance UID, and that the study is on this PACS");
  }
  if (contents.other_classes.empty()) return {};  // nothing endorecon does not take: the whole study
  std::string others;
  for (const auto& [name, count] : contents.other_classes) {
    others += (others.empty() ? "" : ", ") + name + " x " + std::to_string(count);
  }
  if (contents.recording_series.empty()) {
    Fail(ErrorCode::kNotFound,
         "the study holds no recording, only objects of classes endorecon does not take (" + others + ")");
  }
  spdlog::info(
      "job {}: the study holds {} series of other objects ({}): retrieving its {} series of the classes "
      "endorecon takes (recordings, and its own results, taken and not kept) one by one",
      job_id, contents.other_series, others, contents.recording_series.size());
  return contents.recording_series;
}

std::pair<fs::path, std::string> DicomRetriever::Fetch(const std::string& job_id,
                                                       const v1::PacsSource& source) {
  dicom::RetrieveRequest request;
  request.peer = pacs_.Find(source.pacs());
  request.calling_ae_title = settings_.ae_title;
  request.study_uid = source.study_uid();
  request.timeout_s = settings_.timeout_s;
  // The series named, or the whole study; a study that also holds objects of classes endorecon does
  // not take (a CT, a report), which a PACS fails a whole-study retrieval for, series by series.
  const std::vector<std::string> series = source.series_uid().empty()
                                              ? RecordingSeries(job_id, request)
                                              : std::vector<std::string>{source.series_uid()};
  const std::vector<std::string> requests = series.empty() ? std::vector<std::string>{""} : series;
  // Each request in turn; one that finds only endorecon's own results (taken, not kept) brings nothing
  // and the others may still bring the recording.
  const auto each = [&](const std::function<void(const dicom::RetrieveRequest&)>& retrieve) {
    int found = 0;
    std::optional<Error> not_found;
    for (const std::string& one : requests) {
      request.series_uid = one;
      try {
        retrieve(request);
        ++found;
      } catch (const Error& e) {
        if (e.code() != ErrorCode::kNotFound || requests.size() == 1) throw;
        not_found = e;
      }
    }
    if (found == 0) throw *not_found;
  };
  const fs::path folder = work_dir_ / job_id;
  fs::remove_all(folder);
  coordinator_.Update(job_id, [](v1::Job& job) { job.mutable_retrieval()->set_method("C-GET"); });
  std::string get_error;
  try {
    // Each series' progress counts on from the series before it. A failed series brings nothing to
    // count: NOT_FOUND received none, and any other failure turns to C-MOVE, which counts anew.
    int instances_before = 0;
    std::int64_t bytes_before = 0;
    each([&](const dicom::RetrieveRequest& one) {
      int instances = 0;
      std::int64_t bytes = 0;
      dicom::GetStudy(one, folder, [&](int n, std::int64_t b) {
        instances = n;
        bytes = b;
        Progress(job_id, instances_before + n, bytes_before + b);
      });
      instances_before += instances;
      bytes_before += bytes;
    });
    return {folder, "C-GET"};
  } catch (const Error& e) {
    // Not there, or no answer (C-MOVE would get none either): only a refusal turns to C-MOVE.
    if (e.code() == ErrorCode::kNotFound || e.code() == ErrorCode::kUnavailable) throw;
    if (scp_ == nullptr) {
      Fail(e.code(), std::string(e.what()) +
                         "; C-MOVE was not tried: this server has no --dicom-listen for a PACS to send to");
    }
    get_error = e.what();
    spdlog::warn("job {}: C-GET from {} failed ({}); trying C-MOVE to this server's storage SCP", job_id,
                 source.pacs(), get_error);
  }
  fs::remove_all(folder);
  coordinator_.Update(job_id, [](v1::Job& job) { job.mutable_retrieval()->set_method("C-MOVE"); });
  const fs::path study_folder = scp_->settings().folder / source.study_uid();
  fs::remove_all(study_folder);
  {
    std::lock_guard lock(mutex_);
    moving_study_ = source.study_uid();
    moving_job_ = job_id;
    moved_instances_ = 0;
    moved_bytes_ = 0;
  }
  try {
    each([&](const dicom::RetrieveRequest& one) { dicom::MoveStudy(one, settings_.ae_title); });
  } catch (const Error& e) {
    {
      std::lock_guard lock(mutex_);
      moving_job_.clear();
    }
    // Both ways failed: say both, the first is often the telling one.
    Fail(e.code(), "C-GET: " + get_error + "; then C-MOVE: " + e.what());
  } catch (...) {
    std::lock_guard lock(mutex_);
    moving_job_.clear();
    throw;
  }
  {
    std::lock_guard lock(mutex_);
    moving_job_.clear();
  }
  fs::create_directories(folder);
  for (const auto& entry : fs::recursive_directory_iterator(study_folder)) {
    const std::string in_series = entry.path().parent_path().filename().string();
    const bool wanted = series.empty() || std::find(series.begin(), series.end(), in_series) != series.end();
    if (entry.is_regular_file() && entry.path().extension() == ".dcm" && wanted) {
      fs::rename(entry.path(), folder / entry.path().filename());
    }
  }
  fs::remove_all(study_folder);
  return {folder, "C-MOVE"};
}

// Each retrieved file is an entry of the clip, named by its place ("instance-0001.dcm"): the files
// arrive named after their SOP Instance UIDs, which then stood in the job's errors and the logs, and
// a UID leads to a patient (found 2026-12-05). The loader orders a recording by its tags, not by name.
std::vector<std::pair<fs::path, v1::FileEntry>> DicomRetriever::Describe(const fs::path& folder) {
  std::vector<fs::path> files;
  for (const auto& entry : fs::directory_iterator(folder)) {
    if (entry.is_regular_file()) files.push_back(entry.path());
  }
  std::sort(files.begin(), files.end());
  std::vector<std::pair<fs::path, v1::FileEntry>> described;
  for (const auto& file : files) {
    v1::FileEntry entry;
    entry.set_path(fmt::format("instance-{:04}.dcm", described.size() + 1));
    CheckRelativePath(entry.path());
    entry.set_size(static_cast<std::int64_t>(fs::file_size(file)));
    entry.set_sha256(Sha256File(file));
    described.emplace_back(file, std::move(entry));
  }
  return described;
}

// Each file becomes a blob, streamed from disk and verified as uploads are.
void DicomRetriever::StoreBlobs(const std::vector<std::pair<fs::path, v1::FileEntry>>& files) {
  for (const auto& [file, entry] : files) {
    if (blobs_.Has(entry.sha256())) continue;
    auto writer = blobs_.TryOpenWriter(entry, std::chrono::seconds(60));
    if (!writer) continue;  // the same content was being written by another stream, and is now a blob
    std::ifstream in(file, std::ios::binary);
    std::string chunk(1 << 20, '\0');
    std::int64_t offset = 0;
    while (in.read(chunk.data(), static_cast<std::streamsize>(chunk.size())) || in.gcount() > 0) {
      writer->Append(offset, std::string_view(chunk.data(), static_cast<std::size_t>(in.gcount())));
      offset += in.gcount();
    }
    writer->Promote();
  }
}

void DicomRetriever::Run(const std::string& job_id) {
  const v1::Job job = coordinator_.Get(job_id, ServerPrincipal());
  if (job.state() != v1::QUEUED || job.retrieval().state() != v1::Retrieval::RETRIEVING) return;
  if (job.retrieval().next_attempt_unix_ms() > NowUnixMs()) {
    due_.Schedule(job_id, job.retrieval().next_attempt_unix_ms());
    return;
  }
  const auto& source = job.retrieval().source();
  const int attempt = job.retrieval().attempts() + 1;
  coordinator_.Update(job_id, [&](v1::Job& stored) {
    stored.mutable_retrieval()->set_attempts(attempt);
    stored.mutable_retrieval()->set_next_attempt_unix_ms(0);
  });
  spdlog::info("job {}: retrieving its recording from PACS {}{}", job_id, source.pacs(),
               attempt > 1 ? fmt::format(" (attempt {} of {})", attempt, settings_.retrieve_attempts) : "");
  try {
    const auto [folder, method] = Fetch(job_id, source);
    const auto files = Describe(folder);
    if (files.empty()) Fail(ErrorCode::kNotFound, "no instance arrived");
    v1::Manifest clip;
    for (const auto& [file, entry] : files) *clip.add_files() = entry;
    // The job's tenant pays for the recording: refused before any byte enters the blob store.
    coordinator_.CheckRetrievalQuota(job_id, clip);
    StoreBlobs(files);
    fs::remove_all(folder);
    coordinator_.RetrievalDone(job_id, clip);
    audit_("PacsRetrieve", job_id, "OK", source.pacs());
    spdlog::info("job {}: recording retrieved from PACS {} by {}", job_id, source.pacs(), method);
  } catch (const Error& e) {
    std::error_code ignored;
    fs::remove_all(work_dir_ / job_id, ignored);
    audit_("PacsRetrieve", job_id, ErrorCodeName(e.code()), source.pacs());
    if (!Retry(job_id, e, attempt)) {
      coordinator_.RetrievalFailed(job_id, std::string(ErrorCodeName(e.code())) + ": " + e.what());
    }
  }
}

bool DicomRetriever::Retry(const std::string& job_id, const Error& failure, int attempt) {
  if (failure.code() != ErrorCode::kUnavailable || attempt >= settings_.retrieve_attempts) return false;
  const std::int64_t wait_ms = RetryWaitMs(settings_.retrieve_backoff_ms, attempt);
  const std::int64_t next = NowUnixMs() + wait_ms;
  bool waiting = false;
  coordinator_.Update(job_id, [&](v1::Job& stored) {
    if (stored.state() != v1::QUEUED) return;  // cancelled meanwhile
    stored.mutable_retrieval()->set_error(std::string(ErrorCodeName(failure.code())) + ": " + failure.what());
    stored.mutable_retrieval()->set_next_attempt_unix_ms(next);
    waiting = true;
  });
  if (!waiting) return true;
  spdlog::warn("job {}: retrieval from PACS failed (attempt {} of {}), trying again in {:.0f} s: {}", job_id,
               attempt, settings_.retrieve_attempts, wait_ms / 1000.0, failure.what());
  due_.Schedule(job_id, next);
  return true;
}

}  // namespace endorecon::server
