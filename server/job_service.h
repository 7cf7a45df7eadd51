// JobService (proto/endorecon/v1/job_service.proto): the user-facing API, a thin adapter from
// gRPC onto the JobCoordinator, the UploadReceiver and the blob store. Every handler goes through
// the CallGuard (tokens, roles, tenants, audit).
#pragma once

#include <chrono>

#include "endorecon/v1/job_service.grpc.pb.h"
#include "server/call_guard.h"
#include "server/job_coordinator.h"
#include "server/stall_watch.h"
#include "server/upload_receiver.h"

namespace endorecon::server {

class JobServiceImpl final : public v1::JobService::Service {
 public:
  JobServiceImpl(CallGuard& guard, JobCoordinator& coordinator, UploadReceiver& uploads, BlobStore& blobs,
                 WatchHub& hub, WorkerRegistry& workers, Metrics& metrics, StallWatch& stalls);

  grpc::Status QueryUpload(grpc::ServerContext*, const v1::Manifest*, v1::UploadStatus*) override;
  grpc::Status Upload(grpc::ServerContext*, grpc::ServerReader<v1::UploadRequest>*,
                      v1::UploadStatus*) override;
  grpc::Status Submit(grpc::ServerContext*, const v1::SubmitRequest*, v1::Job*) override;
  grpc::Status Get(grpc::ServerContext*, const v1::GetJobRequest*, v1::Job*) override;
  grpc::Status List(grpc::ServerContext*, const v1::ListJobsRequest*, v1::ListJobsResponse*) override;
  grpc::Status Cancel(grpc::ServerContext*, const v1::CancelJobRequest*, v1::Job*) override;
  grpc::Status Delete(grpc::ServerContext*, const v1::DeleteJobRequest*, v1::Job*) override;
  grpc::Status Watch(grpc::ServerContext*, const v1::WatchJobRequest*,
                     grpc::ServerWriter<v1::JobEvent>*) override;
  grpc::Status Fetch(grpc::ServerContext*, const v1::FetchRequest*,
                     grpc::ServerWriter<v1::FileChunk>*) override;
  grpc::Status ListWorkers(grpc::ServerContext*, const v1::ListWorkersRequest*,
                           v1::ListWorkersResponse*) override;
  grpc::Status Send(grpc::ServerContext*, const v1::SendRequest*, v1::Job*) override;
  grpc::Status Drain(grpc::ServerContext*, const v1::DrainRequest*, v1::WorkerInfo*) override;
  grpc::Status Uploads(grpc::ServerContext*, const v1::UploadsRequest*, v1::UploadsResponse*) override;

 private:
  CallGuard& guard_;
  JobCoordinator& coordinator_;
  UploadReceiver& uploads_;
  BlobStore& blobs_;
  WatchHub& hub_;
  WorkerRegistry& workers_;
  Metrics& metrics_;
  StallWatch& stalls_;
};

}  // namespace endorecon::server
