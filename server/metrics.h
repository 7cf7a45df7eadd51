// The server's Prometheus metrics (prometheus-cpp), served at http://<bind>/metrics.
//   endorecon_jobs{state}                    gauge: jobs in each state
//   endorecon_queue_depth                    gauge: queued jobs waiting for a worker
//   endorecon_jobs_submitted_total           counter
//   endorecon_jobs_completed_total           counter: SUCCEEDED
//   endorecon_jobs_failed_total              counter
//   endorecon_jobs_cancelled_total           counter
//   endorecon_job_duration_seconds           histogram: lease to SUCCEEDED of the successful attempt
//   endorecon_upload_bytes_total             counter: bytes committed by uploads (clients and workers)
//   endorecon_download_bytes_total           counter: bytes sent by downloads (results, clips, checkpoints)
//   endorecon_workers_connected              gauge: workers heard from within the liveness window
//   endorecon_lease_expiries_total           counter: leases that expired (worker vanished)
//   endorecon_dicom_instances_sent_total{destination}  counter: instances a PACS confirmed (C-STORE)
//   endorecon_dicom_send_failures_total{destination}   counter: send attempts that failed
//   endorecon_dicom_retrieval_bytes_total    counter: bytes of recordings retrieved from a PACS
//   endorecon_leases_granted_total           counter: jobs handed to a worker (attempts started)
//   endorecon_calls_refused_total{code}      counter: calls refused (UNAUTHENTICATED, PERMISSION_DENIED,
//                                            NOT_FOUND, RESOURCE_EXHAUSTED, ...)
//   endorecon_jobs_expired_total             counter: finished jobs whose files retention deleted
//   endorecon_data_available_bytes           gauge: free bytes on the data folder's file system
//   endorecon_data_capacity_bytes            gauge: size of that file system
//   endorecon_damaged_files                  gauge: stored files set aside as damaged (<data>/damaged)
//   endorecon_audit_write_failures_total     counter: audit log lines that could not be written
//   endorecon_tls_handshake_failures_total   counter: connections whose TLS handshake failed (a
//                                            certificate this server does not trust, plaintext to TLS)
//   endorecon_uploads_pending_bytes          gauge: bytes of the uploads waiting to be submitted, every
//                                            tenant's (`endorecon uploads` lists them by tenant)
//   endorecon_rpc_seconds{method}            histogram: time the server spent on each call, from the
//                                            gate to its status (streams: the whole stream); the time
//                                            a call waits for a server thread is not in it
//   endorecon_store_commit_seconds           histogram: the job store's commits (one transaction and
//                                            its fsyncs for every write staged meanwhile); a writing
//                                            call waits for one or two of them
//   endorecon_token_expiry_timestamp_seconds{token,role}  gauge: when each token that expires does
//                                            (Unix seconds), for tokens not revoked (an expired one
//                                            stays until it is revoked or its label is reused)
#pragma once

#include <prometheus/counter.h>
#include <prometheus/exposer.h>
#include <prometheus/gauge.h>
#include <prometheus/histogram.h>
#include <prometheus/registry.h>

#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "endorecon/v1/job.pb.h"

namespace endorecon::server {

class Metrics {
 public:
  // Serves the metrics on `bind_address` ("127.0.0.1:9464"; port 0 picks one); empty: not served.
  explicit Metrics(const std::string& bind_address);
  // The port actually bound (0 when not served).
  int port() const;

  void JobSubmitted() { submitted_.Increment(); }
  // Counts a job reaching SUCCEEDED, FAILED or CANCELLED; `run_seconds` >= 0 is observed for SUCCEEDED.
  void JobFinished(v1::JobState state, double run_seconds);
  void LeaseExpired() { lease_expiries_.Increment(); }
  void LeaseGranted() { leases_granted_.Increment(); }
  // `code`: the gRPC status name.
  void CallRefused(const std::string& code) { refused_.Add({{"code", code}}).Increment(); }
  void JobsExpired(std::size_t jobs) { expired_.Increment(static_cast<double>(jobs)); }
  void SetDataDisk(std::int64_t available, std::int64_t capacity);
  void SetDamagedFiles(std::size_t files) { damaged_.Set(static_cast<double>(files)); }
  void AuditWriteFailed() { audit_failures_.Increment(); }
  void TlsHandshakeFailed() { handshake_failures_.Increment(); }
  void SetPendingUploads(std::int64_t bytes) { uploads_pending_.Set(static_cast<double>(bytes)); }
  void UploadBytes(std::int64_t bytes) { upload_bytes_.Increment(static_cast<double>(bytes)); }
  void DownloadBytes(std::int64_t bytes) { download_bytes_.Increment(static_cast<double>(bytes)); }
  void SetJobsByState(const std::map<v1::JobState, std::int64_t>& counts);
  void SetQueueDepth(std::size_t depth) { queue_depth_.Set(static_cast<double>(depth)); }
  void SetWorkersConnected(int workers) { workers_connected_.Set(workers); }
  // Starts the per-PACS series at 0, so that rates and alerts see a destination before its first send.
  void DeclarePacs(const std::string& destination) {
    dicom_sent_.Add({{"destination", destination}});
    dicom_send_failures_.Add({{"destination", destination}});
  }
  void DicomInstanceSent(const std::string& destination) {
    dicom_sent_.Add({{"destination", destination}}).Increment();
  }
  void DicomSendFailed(const std::string& destination) {
    dicom_send_failures_.Add({{"destination", destination}}).Increment();
  }
  void RetrievalBytes(std::int64_t bytes) { retrieval_bytes_.Increment(static_cast<double>(bytes)); }
  // `method`: the RPC's name (a literal: few distinct values).
  void CallHandled(const char* method, double seconds);
  void StoreCommitted(double seconds) { store_commit_seconds_.Observe(seconds); }
  // A token not revoked that expires: its label, its role's name and when it expires.
  struct ExpiringToken {
    std::string name;
    std::string role;
    std::int64_t expires_unix_ms = 0;
  };
  // The token expiry series become `tokens`' (a token revoked since loses its series). One caller
  // thread at a time.
  void SetTokenExpiries(const std::vector<ExpiringToken>& tokens);

 private:
  std::shared_ptr<prometheus::Registry> registry_;
  std::unique_ptr<prometheus::Exposer> exposer_;
  prometheus::Family<prometheus::Gauge>& jobs_;
  prometheus::Gauge& queue_depth_;
  prometheus::Counter& submitted_;
  prometheus::Counter& completed_;
  prometheus::Counter& failed_;
  prometheus::Counter& cancelled_;
  prometheus::Histogram& duration_;
  prometheus::Counter& upload_bytes_;
  prometheus::Counter& download_bytes_;
  prometheus::Gauge& workers_connected_;
  prometheus::Counter& lease_expiries_;
  prometheus::Family<prometheus::Counter>& dicom_sent_;
  prometheus::Family<prometheus::Counter>& dicom_send_failures_;
  prometheus::Counter& retrieval_bytes_;
  prometheus::Counter& leases_granted_;
  prometheus::Family<prometheus::Counter>& refused_;
  prometheus::Counter& expired_;
  prometheus::Gauge& data_available_;
  prometheus::Gauge& data_capacity_;
  prometheus::Gauge& damaged_;
  prometheus::Counter& audit_failures_;
  prometheus::Counter& handshake_failures_;
  prometheus::Gauge& uploads_pending_;
  prometheus::Family<prometheus::Histogram>& rpc_seconds_;
  prometheus::Histogram& store_commit_seconds_;
  prometheus::Family<prometheus::Gauge>& token_expiry_;
  std::map<std::pair<std::string, std::string>, prometheus::Gauge*> token_gauges_;  // (label, role)
};

}  // namespace endorecon::server
