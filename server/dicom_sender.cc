#include "server/dicom_sender.h"

#include <spdlog/spdlog.h>

#include <set>

#include "common/dicom/store_scu.h"
#include "common/error.h"
#include "server/job_states.h"

namespace endorecon::server {
namespace {

v1::DicomSend* Find(v1::Job& job, const std::string& destination) {
  for (auto& send : *job.mutable_sends()) {
    if (send.destination() == destination) return &send;
  }
  return nullptr;
}

}  // namespace

DicomSender::DicomSender(JobCoordinator& coordinator, BlobStore& blobs, const PacsDirectory& pacs,
                         const DicomSettings& settings, Metrics& metrics, PacsAudit audit)
    : coordinator_(coordinator),
      blobs_(blobs),
      pacs_(pacs),
      settings_(settings),
      metrics_(metrics),
      audit_(std::move(audit)),
      due_([this](const Key& key) {
        try {
          Attempt(key.first, key.second);
        } catch (const std::exception& e) {
          spdlog::error("job {}: sending to {}: {}", key.first, key.second, e.what());
        }
      }) {}

void DicomSender::Send(const std::string& job_id) {
  const v1::Job job = coordinator_.Get(job_id, ServerPrincipal());
  if (job.state() != v1::SUCCEEDED) return;
  for (const auto& send : job.sends()) {
    if (SendWaiting(send)) due_.Schedule({job_id, send.destination()}, send.next_attempt_unix_ms());
  }
}

void DicomSender::Attempt(const std::string& job_id, const std::string& destination) {
  std::vector<std::string> paths;
  std::vector<std::filesystem::path> files;
  v1::Job job = coordinator_.Update(job_id, [&](v1::Job& stored) {
    v1::DicomSend* send = Find(stored, destination);
    if (send == nullptr || !SendWaiting(*send)) return;
    const std::set<std::string> sent(send->sent_paths().begin(), send->sent_paths().end());
    int total = 0;
    for (const auto& file : stored.result().files()) {
      if (file.path().rfind("dicom/", 0) != 0) continue;
      ++total;
      if (sent.count(file.path())) continue;
      paths.push_back(file.path());
      files.push_back(blobs_.PathOf(file.sha256()));
    }
    send->set_state(v1::DicomSend::SENDING);
    send->set_total(total);
    send->set_attempts(send->attempts() + 1);
  });
  const v1::DicomSend* send = Find(job, destination);
  if (send == nullptr || send->state() != v1::DicomSend::SENDING) return;
  const int attempt = send->attempts();
  spdlog::info("job {}: sending {} DICOM instance(s) to {} (attempt {})", job_id, files.size(), destination,
               attempt);
  std::string failure;
  try {
    if (send->total() == 0) Fail(ErrorCode::kFailedPrecondition, "the job has no DICOM results");
    dicom::StoreSettings settings;
    settings.calling_ae_title = settings_.ae_title;
    settings.timeout_s = settings_.timeout_s;
    const auto result = dicom::StoreFiles(
        pacs_.Find(destination), files, settings,
        [&](std::size_t i) {
          metrics_.DicomInstanceSent(destination);
          coordinator_.Update(job_id, [&](v1::Job& stored) {
            v1::DicomSend* s = Find(stored, destination);
            s->add_sent_paths(paths[i]);
            s->set_sent(s->sent_paths_size());
          });
        },
        paths);
    failure = result.first_error;
  } catch (const Error& e) {
    failure = e.what();
  }
  // A permanent rejection of the association (an AE title the PACS does not know) is not retried:
  // it stays so until someone changes a configuration.
  const bool permanent = failure.find("Rejected Permanent") != std::string::npos;
  const bool retry = !failure.empty() && !permanent && attempt < settings_.send_attempts;
  const std::int64_t next = NowUnixMs() + RetryWaitMs(settings_.send_backoff_ms, attempt);
  coordinator_.Update(job_id, [&](v1::Job& stored) {
    v1::DicomSend* s = Find(stored, destination);
    if (failure.empty()) {
      s->set_state(v1::DicomSend::SENT);
      s->clear_error();
      s->set_next_attempt_unix_ms(0);
    } else {
      s->set_state(retry ? v1::DicomSend::PENDING : v1::DicomSend::SEND_FAILED);
      s->set_error(failure);
      s->set_next_attempt_unix_ms(retry ? next : 0);
    }
  });
  audit_("PacsSend", job_id, failure.empty() ? "OK" : "FAILED", destination);
  if (failure.empty()) {
    spdlog::info("job {}: DICOM results sent to {}", job_id, destination);
    return;
  }
  metrics_.DicomSendFailed(destination);
  // The log says whether another attempt follows: "attempt 1 of 5" was said of a rejection that is
  // not retried (found 2026-12-07).
  spdlog::warn("job {}: sending to {} failed (attempt {} of {}{}): {}", job_id, destination, attempt,
               settings_.send_attempts,
               retry       ? "; retried"
               : permanent ? "; not retried: the PACS rejected the association permanently"
                           : "; the last",
               failure);
  if (retry) due_.Schedule({job_id, destination}, next);
}

}  // namespace endorecon::server
