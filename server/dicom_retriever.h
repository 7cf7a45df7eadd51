// Retrieves the recordings of jobs submitted by Study UID from their PACS, one job at a time in a
// thread of its own: C-GET into <data>/retrievals/<job>/, or, when the PACS refuses C-GET and the
// server runs its storage SCP, C-MOVE to it. The files become blobs and the job's clip, and the job
// is queued; the job's `retrieval` shows instances and bytes as they arrive. A PACS that does not
// answer (UNAVAILABLE: down, restarting, unreachable) is tried again, `retrieve_attempts` in all,
// waiting as sends do (retrieve_backoff_ms, doubled, at most a minute); the job stays QUEUED and its
// `retrieval` RETRIEVING, with the last reason and the next attempt's time, saved so that a restart
// keeps to it. Any other failure (a refusal, a study it does not hold) FAILS the job at once with the
// PACS's reason; so does a recording that would take the job's tenant over its byte quota (checked
// before the files enter the blob store).
#pragma once

#include <filesystem>
#include <mutex>
#include <string>
#include <vector>

#include "common/dicom/retrieve_scu.h"
#include "common/dicom/storage_scp.h"
#include "common/error.h"
#include "server/blob_store.h"
#include "server/due_queue.h"
#include "server/job_coordinator.h"
#include "server/metrics.h"
#include "server/pacs_directory.h"

namespace endorecon::server {

class DicomRetriever {
 public:
  // `scp` (may be null) is the server's storage SCP, whose folder C-MOVE fills.
  DicomRetriever(JobCoordinator& coordinator, BlobStore& blobs, const PacsDirectory& pacs,
                 const DicomSettings& settings, Metrics& metrics, std::filesystem::path work_dir,
                 const dicom::StorageScp* scp, PacsAudit audit);
  DicomRetriever(const DicomRetriever&) = delete;
  DicomRetriever& operator=(const DicomRetriever&) = delete;

  // Queues the job's retrieval, at the time of its next attempt when one failed before.
  void Retrieve(const std::string& job_id);
  // The storage SCP received an instance (for the progress of a C-MOVE).
  void Received(const std::string& study_uid, std::int64_t bytes);
  // Whether a C-MOVE of this study is in progress (the storage SCP stores nothing else).
  bool Awaits(const std::string& study_uid) const;

 private:
  void Run(const std::string& job_id);
  // After a failed attempt: schedules the next one and returns true, or returns false when the
  // failure is not one to wait out or the attempts are used up.
  bool Retry(const std::string& job_id, const Error& failure, int attempt);
  // The series of a study to retrieve one by one, when it also holds objects endorecon does not take;
  // empty: the whole study at once. Throws Error(kNotFound) when it holds no recording at all.
  std::vector<std::string> RecordingSeries(const std::string& job_id, const dicom::RetrieveRequest& request);
  // Returns the folder holding the retrieved files and the method used.
  std::pair<std::filesystem::path, std::string> Fetch(const std::string& job_id,
                                                      const v1::PacsSource& source);
  std::vector<std::pair<std::filesystem::path, v1::FileEntry>> Describe(const std::filesystem::path& folder);
  void StoreBlobs(const std::vector<std::pair<std::filesystem::path, v1::FileEntry>>& files);
  void Progress(const std::string& job_id, int instances, std::int64_t bytes);

  JobCoordinator& coordinator_;
  BlobStore& blobs_;
  const PacsDirectory& pacs_;
  DicomSettings settings_;
  Metrics& metrics_;
  std::filesystem::path work_dir_;
  const dicom::StorageScp* scp_;
  PacsAudit audit_;

  mutable std::mutex mutex_;  // guards the C-MOVE's state below
  // The C-MOVE in progress: its study, job and what arrived so far.
  std::string moving_study_, moving_job_;
  int moved_instances_ = 0;
  std::int64_t moved_bytes_ = 0;
  // Last: its thread stops (after the retrieval in progress) before the rest goes.
  DueQueue<std::string> due_;
};

}  // namespace endorecon::server
