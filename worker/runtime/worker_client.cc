#include "worker/runtime/worker_client.h"

#include <spdlog/spdlog.h>

#include <algorithm>

#include "common/error.h"
#include "common/file_download.h"
#include "common/file_upload.h"
#include "common/grpc_status.h"
#include "endorecon_version.h"

namespace endorecon::worker {

WorkerClient::WorkerClient(const std::string& server, const ChannelSecurity& security, std::string worker_id,
                           std::chrono::milliseconds timeout)
    : channel_(OpenChannel(server, security)),
      stub_(v1::WorkerService::NewStub(channel_)),
      worker_id_(std::move(worker_id)),
      timeout_(timeout) {}

v1::RegisterResponse WorkerClient::Register(const std::string& hostname, const std::vector<Device>& devices) {
  v1::RegisterRequest request;
  request.set_worker_id(worker_id_);
  request.set_hostname(hostname);
  for (const auto& device : devices) {
    request.add_devices(device.name);
    auto* info = request.add_device_info();
    info->set_name(device.name);
    info->set_kind(device.kind);
    info->set_model(device.description.model);
    info->set_memory_bytes(device.description.memory_bytes);
    info->set_threads(device.threads);
  }
  request.set_version(ENDORECON_VERSION);
  return Send(request);
}

void WorkerClient::Leave() {
  v1::LeaveRequest request;
  request.set_worker_id(worker_id_);
  v1::LeaveResponse response;
  auto context = CallContext(std::min(timeout_, std::chrono::milliseconds(2000)));
  const auto status = stub_->Leave(context.get(), request, &response);
  if (!status.ok())
    spdlog::info("could not tell the server this worker is stopping: {}", status.error_message());
}

v1::RegisterResponse WorkerClient::Send(const v1::RegisterRequest& request) {
  v1::RegisterResponse response;
  auto context = CallContext(timeout_);
  ThrowIfFailed(stub_->Register(context.get(), request, &response), "register");
  std::lock_guard lock(mutex_);
  registration_ = request;
  return response;
}

void WorkerClient::RegisterAgain() {
  v1::RegisterRequest request;
  {
    std::lock_guard lock(mutex_);
    if (!registration_) return;
    request = *registration_;
  }
  request.set_again(true);
  try {
    Send(request);
    spdlog::info("registered again with the server (it restarted since)");
  } catch (const Error& e) {
    spdlog::warn("registering again with the server failed ({}); its next answer asks again", e.what());
    // A server that does not know the worker answers its lease at once: without a pause, a
    // registration that keeps failing would make lease and register a tight loop.
    PauseBeforeRetry(std::chrono::seconds(1));
  }
}

std::optional<v1::LeaseResponse> WorkerClient::Lease(const std::string& device,
                                                     std::chrono::milliseconds wait) {
  v1::LeaseRequest request;
  request.set_worker_id(worker_id_);
  request.set_device(device);
  request.set_wait_ms(wait.count());
  auto context = CallContext(wait + timeout_);
  {
    std::lock_guard lock(mutex_);
    if (cancelled_) return std::nullopt;
    leasing_.insert(context.get());
  }
  v1::LeaseResponse response;
  const auto status = stub_->Lease(context.get(), request, &response);
  {
    std::lock_guard lock(mutex_);
    leasing_.erase(context.get());
    if (cancelled_) return std::nullopt;
  }
  ThrowIfFailed(status, "lease");
  if (response.register_again()) RegisterAgain();
  if (!response.has_job()) return std::nullopt;
  return response;
}

void WorkerClient::CancelLeases() {
  std::lock_guard lock(mutex_);
  cancelled_ = true;
  for (auto* context : leasing_) context->TryCancel();
}

v1::Job WorkerClient::Complete(const v1::CompleteRequest& request) {
  v1::Job job;
  auto context = CallContext(timeout_);
  ThrowIfFailed(stub_->Complete(context.get(), request, &job), "complete");
  return job;
}

v1::Job WorkerClient::CompleteWithResults(const std::filesystem::path& dir,
                                          const v1::CompleteRequest& request) {
  try {
    return Complete(request);
  } catch (const Error& e) {
    if (e.code() != ErrorCode::kFailedPrecondition) throw;
    spdlog::warn("the server refused the results ({}); sending what it lacks again", e.what());
    PutFiles(dir, request.result());
    return Complete(request);
  }
}

v1::Job WorkerClient::Fail(const v1::FailRequest& request) {
  v1::Job job;
  auto context = CallContext(timeout_);
  ThrowIfFailed(stub_->Fail(context.get(), request, &job), "fail");
  return job;
}

void WorkerClient::PutFiles(const std::filesystem::path& dir, const v1::Manifest& manifest) {
  UploadCalls calls;
  calls.query = [&](grpc::ClientContext* context, const v1::Manifest& m, v1::UploadStatus* status) {
    return stub_->QueryBlobs(context, m, status);
  };
  calls.open = [&](grpc::ClientContext* context, v1::UploadStatus* status) {
    return stub_->PutBlobs(context, status);
  };
  UploadOptions options;
  options.call_timeout = timeout_;
  UploadFiles(dir, manifest, calls, options);
}

void WorkerClient::GetFiles(const std::string& lease_id, const std::filesystem::path& dir,
                            const v1::Manifest& manifest) {
  const auto pending = PendingDownloads(dir, manifest);
  if (pending.empty()) return;
  v1::GetBlobsRequest request;
  request.set_lease_id(lease_id);
  std::int64_t bytes = 0;
  for (const auto& range : OnePerContent(pending)) *request.add_files() = range;
  for (const auto& file : manifest.files()) bytes += file.size();
  auto context = CallContext(timeout_ + std::chrono::milliseconds(bytes / 1000));  // at least 1 MB/s
  auto reader = stub_->GetBlobs(context.get(), request);
  ReceiveFiles(*reader, dir);
  CopyDuplicates(dir, pending);
}

std::unique_ptr<grpc::ClientReaderWriter<v1::ProgressUpdate, v1::ProgressReply>> WorkerClient::OpenReport(
    grpc::ClientContext* context) {
  return stub_->Report(context);
}

}  // namespace endorecon::worker
