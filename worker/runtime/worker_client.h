// The worker's side of WorkerService: every call with a deadline, blob moves through the shared
// resumable upload/download code, and long polls that can be cancelled at shutdown.
#pragma once

#include <chrono>
#include <filesystem>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "common/transport_security.h"
#include "endorecon/v1/worker_service.grpc.pb.h"
#include "worker/runtime/device_list.h"

namespace endorecon::worker {

class WorkerClient {
 public:
  // Throws as OpenChannel for bad TLS files.
  WorkerClient(const std::string& server, const ChannelSecurity& security, std::string worker_id,
               std::chrono::milliseconds timeout);

  const std::string& worker_id() const { return worker_id_; }
  v1::RegisterResponse Register(const std::string& hostname, const std::vector<Device>& devices);
  // Tells the server this worker is stopping (it is then listed as not alive at once). Best effort:
  // a server away or refusing is logged, not thrown; the worker stops either way.
  void Leave();
  // Waits up to `wait` for a job; nullopt when none came (or CancelLeases() was called).
  std::optional<v1::LeaseResponse> Lease(const std::string& device, std::chrono::milliseconds wait);
  // Ends every Lease call in flight (at shutdown).
  void CancelLeases();
  // The wait before a failed call is tried again (endorecon::PauseBeforeRetry on its channel).
  void PauseBeforeRetry(std::chrono::milliseconds pause) { endorecon::PauseBeforeRetry(*channel_, pause); }
  // Registers again as last time, when a lease or report says the server does not know the worker
  // (it restarted and lost the worker's devices). A failure is logged and paused on (a second at
  // most, PauseBeforeRetry); the next answer asks again.
  void RegisterAgain();
  v1::Job Complete(const v1::CompleteRequest& request);
  // Complete, with the results already uploaded from `dir` (PutFiles). A worker serving one tenant
  // shows that its results are its own by sending them (the server's BlobHolders); a server restarted
  // between the upload and the Complete forgot that and refuses them as not uploaded
  // (FAILED_PRECONDITION): they are sent once more, and the Complete tried again. A lease lost
  // meanwhile is refused the same way twice, and thrown.
  v1::Job CompleteWithResults(const std::filesystem::path& dir, const v1::CompleteRequest& request);
  v1::Job Fail(const v1::FailRequest& request);
  // Uploads the files of `manifest` from `dir` (only what the server lacks).
  void PutFiles(const std::filesystem::path& dir, const v1::Manifest& manifest);
  // Downloads the files of `manifest` into `dir` (verified, resuming partial files).
  void GetFiles(const std::string& lease_id, const std::filesystem::path& dir, const v1::Manifest& manifest);
  // A Report stream; the caller owns `context` and must outlive the stream with it.
  std::unique_ptr<grpc::ClientReaderWriter<v1::ProgressUpdate, v1::ProgressReply>> OpenReport(
      grpc::ClientContext* context);

 private:
  std::shared_ptr<grpc::Channel> channel_;
  std::unique_ptr<v1::WorkerService::Stub> stub_;
  std::string worker_id_;
  std::chrono::milliseconds timeout_;
  std::mutex mutex_;
  std::set<grpc::ClientContext*> leasing_;
  bool cancelled_ = false;
  std::optional<v1::RegisterRequest> registration_;  // the last Register's, for RegisterAgain()
  // The Register call; keeps `request` for RegisterAgain().
  v1::RegisterResponse Send(const v1::RegisterRequest& request);
};

}  // namespace endorecon::worker
