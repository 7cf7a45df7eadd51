#include "server/metrics.h"

#include "common/metrics_exposer.h"

namespace endorecon::server {
namespace {

using prometheus::BuildCounter;
using prometheus::BuildGauge;
using prometheus::BuildHistogram;

prometheus::Counter& Counter(prometheus::Registry& registry, const std::string& name,
                             const std::string& help) {
  return BuildCounter().Name(name).Help(help).Register(registry).Add({});
}

prometheus::Gauge& Gauge(prometheus::Registry& registry, const std::string& name, const std::string& help) {
  return BuildGauge().Name(name).Help(help).Register(registry).Add({});
}

}  // namespace

Metrics::Metrics(const std::string& bind_address)
    : registry_(std::make_shared<prometheus::Registry>()),
      jobs_(BuildGauge().Name("endorecon_jobs").Help("Jobs in each state").Register(*registry_)),
      queue_depth_(Gauge(*registry_, "endorecon_queue_depth", "Queued jobs waiting for a worker")),
      submitted_(Counter(*registry_, "endorecon_jobs_submitted_total", "Jobs submitted")),
      completed_(Counter(*registry_, "endorecon_jobs_completed_total", "Jobs that succeeded")),
      failed_(Counter(*registry_, "endorecon_jobs_failed_total", "Jobs that failed")),
      cancelled_(Counter(*registry_, "endorecon_jobs_cancelled_total", "Jobs cancelled")),
      duration_(BuildHistogram()
                    .Name("endorecon_job_duration_seconds")
                    .Help("Run time of successful jobs, from lease to completion")
                    .Register(*registry_)
                    .Add({}, prometheus::Histogram::BucketBoundaries{10, 30, 60, 120, 300, 600, 1800, 3600,
                                                                     7200, 14400, 43200, 86400})),
      upload_bytes_(Counter(*registry_, "endorecon_upload_bytes_total", "Bytes committed by uploads")),
      download_bytes_(Counter(*registry_, "endorecon_download_bytes_total", "Bytes sent by downloads")),
      workers_connected_(Gauge(*registry_, "endorecon_workers_connected", "Workers heard from recently")),
      lease_expiries_(Counter(*registry_, "endorecon_lease_expiries_total", "Leases that expired")),
      dicom_sent_(BuildCounter()
                      .Name("endorecon_dicom_instances_sent_total")
                      .Help("DICOM instances a PACS confirmed storing (C-STORE)")
                      .Register(*registry_)),
      dicom_send_failures_(BuildCounter()
                               .Name("endorecon_dicom_send_failures_total")
                               .Help("Attempts to send DICOM results to a PACS that failed")
                               .Register(*registry_)),
      retrieval_bytes_(Counter(*registry_, "endorecon_dicom_retrieval_bytes_total",
                               "Bytes of recordings retrieved from a PACS")),
      leases_granted_(Counter(*registry_, "endorecon_leases_granted_total", "Jobs handed to a worker")),
      refused_(BuildCounter()
                   .Name("endorecon_calls_refused_total")
                   .Help("Calls refused, by gRPC status")
                   .Register(*registry_)),
      expired_(Counter(*registry_, "endorecon_jobs_expired_total",
                       "Finished jobs whose files retention or a delete removed")),
      data_available_(
          Gauge(*registry_, "endorecon_data_available_bytes", "Free bytes on the data folder's file system")),
      data_capacity_(
          Gauge(*registry_, "endorecon_data_capacity_bytes", "Size of the data folder's file system")),
      damaged_(Gauge(*registry_, "endorecon_damaged_files",
                     "Stored files set aside as damaged, their bytes no longer matching their digest (a disk "
                     "fault), in the data folder's damaged/")),
      audit_failures_(Counter(*registry_, "endorecon_audit_write_failures_total",
                              "Audit log lines that could not be written (a full or failing disk): calls "
                              "that happened without their audit record")),
      handshake_failures_(
          Counter(*registry_, "endorecon_tls_handshake_failures_total",
                  "Connections whose TLS handshake failed (a client or worker certificate this "
                  "server does not trust, plaintext to the TLS port): refused before any call")),
      uploads_pending_(Gauge(*registry_, "endorecon_uploads_pending_bytes",
                             "Bytes of the uploads waiting to be submitted, every tenant's")),
      rpc_seconds_(BuildHistogram()
                       .Name("endorecon_rpc_seconds")
                       .Help("Time the server spent on each call, by method (streams: the whole stream)")
                       .Register(*registry_)),
      store_commit_seconds_(
          BuildHistogram()
              .Name("endorecon_store_commit_seconds")
              .Help("Duration of the job store's commits (a transaction and its fsyncs)")
              .Register(*registry_)
              .Add({}, prometheus::Histogram::BucketBoundaries{0.001, 0.0025, 0.005, 0.01, 0.025, 0.05, 0.1,
                                                               0.25, 0.5, 1, 2.5, 10})),
      token_expiry_(BuildGauge()
                        .Name("endorecon_token_expiry_timestamp_seconds")
                        .Help("When each token that expires does (Unix seconds), for tokens not revoked")
                        .Register(*registry_)) {
  for (const auto* code : {"UNAUTHENTICATED", "PERMISSION_DENIED"}) refused_.Add({{"code", code}});
  for (const auto state : {v1::QUEUED, v1::RUNNING, v1::SUCCEEDED, v1::FAILED, v1::CANCELLED}) {
    jobs_.Add({{"state", v1::JobState_Name(state)}}).Set(0);
  }
  if (!bind_address.empty()) {
    exposer_ = OpenMetricsExposer(bind_address);
    exposer_->RegisterCollectable(registry_);
  }
}

int Metrics::port() const { return exposer_ ? exposer_->GetListeningPorts().at(0) : 0; }

void Metrics::JobFinished(v1::JobState state, double run_seconds) {
  if (state == v1::SUCCEEDED) {
    completed_.Increment();
    if (run_seconds >= 0) duration_.Observe(run_seconds);
  } else if (state == v1::FAILED) {
    failed_.Increment();
  } else if (state == v1::CANCELLED) {
    cancelled_.Increment();
  }
}

void Metrics::SetDataDisk(std::int64_t available, std::int64_t capacity) {
  data_available_.Set(static_cast<double>(available));
  data_capacity_.Set(static_cast<double>(capacity));
}

void Metrics::SetJobsByState(const std::map<v1::JobState, std::int64_t>& counts) {
  for (const auto state : {v1::QUEUED, v1::RUNNING, v1::SUCCEEDED, v1::FAILED, v1::CANCELLED}) {
    const auto found = counts.find(state);
    jobs_.Add({{"state", v1::JobState_Name(state)}})
        .Set(found == counts.end() ? 0.0 : static_cast<double>(found->second));
  }
}

void Metrics::SetTokenExpiries(const std::vector<ExpiringToken>& tokens) {
  std::map<std::pair<std::string, std::string>, prometheus::Gauge*> now;
  for (const auto& token : tokens) {
    const std::pair key{token.name, token.role};
    auto found = token_gauges_.find(key);
    prometheus::Gauge* gauge = found != token_gauges_.end()
                                   ? found->second
                                   : &token_expiry_.Add({{"token", token.name}, {"role", token.role}});
    gauge->Set(static_cast<double>(token.expires_unix_ms) / 1000.0);
    now[key] = gauge;
  }
  for (const auto& [key, gauge] : token_gauges_) {
    if (!now.count(key)) token_expiry_.Remove(gauge);
  }
  token_gauges_ = std::move(now);
}

void Metrics::CallHandled(const char* method, double seconds) {
  static const prometheus::Histogram::BucketBoundaries kBounds{0.001, 0.0025, 0.005, 0.01, 0.025, 0.05, 0.1,
                                                               0.25,  0.5,    1,     2.5,  10,    60};
  rpc_seconds_.Add({{"method", method}}, kBounds).Observe(seconds);
}

}  // namespace endorecon::server
