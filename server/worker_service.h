// WorkerService (proto/endorecon/v1/worker_service.proto): the worker-facing API, a thin adapter
// from gRPC onto the JobCoordinator, the UploadReceiver and the blob store. Every handler goes
// through the CallGuard (worker tokens, client certificates, audit).
#pragma once

#include <chrono>

#include "endorecon/v1/worker_service.grpc.pb.h"
#include "server/call_guard.h"
#include "server/job_coordinator.h"
#include "server/stall_watch.h"
#include "server/upload_receiver.h"

namespace endorecon::server {

struct WorkerTiming {
  std::chrono::milliseconds lease_ttl{30000};
  std::chrono::milliseconds heartbeat_interval{2000};
  std::chrono::milliseconds max_lease_wait{20000};  // longest long-poll the server holds
};

class WorkerServiceImpl final : public v1::WorkerService::Service {
 public:
  WorkerServiceImpl(CallGuard& guard, JobCoordinator& coordinator, UploadReceiver& uploads, BlobStore& blobs,
                    WorkerRegistry& workers, Metrics& metrics, StallWatch& stalls, WorkerTiming timing);

  grpc::Status Register(grpc::ServerContext*, const v1::RegisterRequest*, v1::RegisterResponse*) override;
  grpc::Status Leave(grpc::ServerContext*, const v1::LeaveRequest*, v1::LeaveResponse*) override;
  grpc::Status Lease(grpc::ServerContext*, const v1::LeaseRequest*, v1::LeaseResponse*) override;
  grpc::Status Report(grpc::ServerContext*,
                      grpc::ServerReaderWriter<v1::ProgressReply, v1::ProgressUpdate>* stream) override;
  grpc::Status Complete(grpc::ServerContext*, const v1::CompleteRequest*, v1::Job*) override;
  grpc::Status Fail(grpc::ServerContext*, const v1::FailRequest*, v1::Job*) override;
  grpc::Status QueryBlobs(grpc::ServerContext*, const v1::Manifest*, v1::UploadStatus*) override;
  grpc::Status PutBlobs(grpc::ServerContext*, grpc::ServerReader<v1::UploadRequest>*,
                        v1::UploadStatus*) override;
  grpc::Status GetBlobs(grpc::ServerContext*, const v1::GetBlobsRequest*,
                        grpc::ServerWriter<v1::FileChunk>*) override;

 private:
  CallGuard& guard_;
  JobCoordinator& coordinator_;
  UploadReceiver& uploads_;
  BlobStore& blobs_;
  WorkerRegistry& workers_;
  Metrics& metrics_;
  StallWatch& stalls_;
  WorkerTiming timing_;
};

}  // namespace endorecon::server
