// Sends the DICOM results (the dicom/ files of a job's results) of SUCCEEDED jobs to PACS, with
// C-STORE, in a thread of its own. Each destination of a job (its entry in `sends`) goes PENDING
// -> SENDING -> SENT, or back to PENDING after a failure (attempt n waits send_backoff_ms x 2^(n-1),
// at most 60 s) and SEND_FAILED with the peer's reason once `send_attempts` are used up; the job
// stays SUCCEEDED and `endorecon send` starts again. Instances the PACS confirmed are recorded
// (sent_paths) and not sent again. Every change is saved in the job store before it is acted on,
// so a restart resumes PENDING and SENDING sends.
#pragma once

#include <string>
#include <utility>

#include "server/blob_store.h"
#include "server/due_queue.h"
#include "server/job_coordinator.h"
#include "server/metrics.h"
#include "server/pacs_directory.h"

namespace endorecon::server {

class DicomSender {
 public:
  DicomSender(JobCoordinator& coordinator, BlobStore& blobs, const PacsDirectory& pacs,
              const DicomSettings& settings, Metrics& metrics, PacsAudit audit);
  DicomSender(const DicomSender&) = delete;
  DicomSender& operator=(const DicomSender&) = delete;

  // Schedules every PENDING or SENDING destination of the job (at its next attempt time).
  void Send(const std::string& job_id);

 private:
  using Key = std::pair<std::string, std::string>;  // job, destination
  void Attempt(const std::string& job_id, const std::string& destination);

  JobCoordinator& coordinator_;
  BlobStore& blobs_;
  const PacsDirectory& pacs_;
  DicomSettings settings_;
  Metrics& metrics_;
  PacsAudit audit_;

  DueQueue<Key> due_;  // last: its thread stops (after the attempt in progress) before the rest goes
};

}  // namespace endorecon::server
