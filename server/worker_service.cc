#include "server/worker_service.h"

#include <spdlog/spdlog.h>

#include <filesystem>
#include <map>
#include <optional>
#include <set>

#include "common/error.h"
#include "common/job_bounds.h"
#include "endorecon_version.h"
#include "server/file_sender.h"

namespace endorecon::server {

WorkerServiceImpl::WorkerServiceImpl(CallGuard& guard, JobCoordinator& coordinator, UploadReceiver& uploads,
                                     BlobStore& blobs, WorkerRegistry& workers, Metrics& metrics,
                                     StallWatch& stalls, WorkerTiming timing)
    : guard_(guard),
      coordinator_(coordinator),
      uploads_(uploads),
      blobs_(blobs),
      workers_(workers),
      metrics_(metrics),
      stalls_(stalls),
      timing_(timing) {}

namespace {

// The worker id a Register or Leave names, for the audit log's `subject`: as it is when it is one.
std::string AuditedWorkerId(const std::string& id) {
  try {
    ValidateWorkerId(id);
    return id;
  } catch (const Error&) {
    return "(not a worker id)";
  }
}

// A worker's calls carry another token than it registered with: a rotation, or a second worker
// claiming its id. The server cannot tell which; the operator can (the audit log has both tokens).
void WarnOfTokenChange(const std::string& worker_id, const std::string& token, const std::string& before) {
  if (before.empty()) return;
  spdlog::warn(
      "worker {}: its calls carry token '{}', it registered with '{}': a rotated token, or two workers "
      "sharing one --id",
      AuditedWorkerId(worker_id), token, before);
}

// Server and workers check a job's --config alike (a key a newer worker knows is refused by an older
// server): a worker of another build is said once it registers, as an operator upgrading part of a
// cluster would want to know.
void WarnOfOtherVersion(const v1::RegisterRequest& request) {
  if (request.version() == ENDORECON_VERSION) return;
  spdlog::warn("worker {} runs endorecon {}, this server {}: deploy server and workers at one version",
               AuditedWorkerId(request.worker_id()),
               request.version().empty() ? std::string("of an unnamed version") : request.version(),
               ENDORECON_VERSION);
}

// The one tenant whose jobs a worker's token serves (`token create --role worker --tenant T`: a
// research department's GPU node that must not see clinical recordings); nullopt: every tenant's.
std::optional<std::string> ServedTenant(const Principal& caller) {
  if (caller.anonymous || caller.tenant.empty()) return std::nullopt;
  return caller.tenant;
}

// The token a worker's call carried, for its lease (an anonymous caller's never expires).
LeaseToken TokenOf(const Principal& caller) {
  if (caller.anonymous) return {};
  return {caller.name, caller.token_expires_unix_ms};
}

}  // namespace

grpc::Status WorkerServiceImpl::Register(grpc::ServerContext* context, const v1::RegisterRequest* request,
                                         v1::RegisterResponse* response) {
  return guard_.Run(context,
                    {"Register", Access::kWorker, kWrites, "", AuditedWorkerId(request->worker_id())},
                    [&](Call& call) {
                      ValidateWorkerId(request->worker_id());
                      // What a worker says of itself is listed by `endorecon workers`: printable, as its id.
                      v1::RegisterRequest registered = *request;
                      registered.set_hostname(PrintableText(registered.hostname(), kMaxWorkerIdBytes));
                      registered.set_version(PrintableText(registered.version(), kMaxWorkerIdBytes));
                      for (auto& device : *registered.mutable_devices()) device = PrintableText(device, 1024);
                      for (auto& info : *registered.mutable_device_info()) {
                        info.set_name(PrintableText(info.name(), 1024));
                        info.set_kind(PrintableText(info.kind(), 64));
                        info.set_model(PrintableText(info.model(), 1024));
                      }
                      WarnOfOtherVersion(registered);
                      WarnOfTokenChange(request->worker_id(), call.caller.name,
                                        workers_.Register(registered, call.caller.name,
                                                          ServedTenant(call.caller).value_or("")));
                      response->set_lease_ttl_ms(timing_.lease_ttl.count());
                      response->set_heartbeat_interval_ms(timing_.heartbeat_interval.count());
                      return grpc::Status::OK;
                    });
}

grpc::Status WorkerServiceImpl::Leave(grpc::ServerContext* context, const v1::LeaveRequest* request,
                                      v1::LeaveResponse*) {
  return guard_.Run(context, {"Leave", Access::kWorker, kWrites, "", AuditedWorkerId(request->worker_id())},
                    [&](Call&) {
                      if (request->worker_id().empty()) FailInvalid("worker_id is empty");
                      workers_.Leave(request->worker_id());
                      return grpc::Status::OK;
                    });
}

grpc::Status WorkerServiceImpl::Lease(grpc::ServerContext* context, const v1::LeaseRequest* request,
                                      v1::LeaseResponse* response) {
  const Rpc rpc{"Lease", Access::kWorker, kReads, ""};
  return guard_.Run(context, rpc, [&](Call& call) {
    // The id goes into job records and `workers` as Register's does: the same rules (a Lease took
    // an id holding escape sequences, which then reached terminals in a job's reason; found
    // 2026-12-06), and a change of token is logged.
    ValidateWorkerId(request->worker_id());
    WarnOfTokenChange(
        request->worker_id(), call.caller.name,
        workers_.NoteToken(request->worker_id(), call.caller.name, ServedTenant(call.caller).value_or("")));
    const auto wait = std::min(std::chrono::milliseconds(std::max<std::int64_t>(request->wait_ms(), 0)),
                               timing_.max_lease_wait);
    // Answer a little before the caller's deadline, so an empty poll is not an error.
    const auto caller_left = std::chrono::duration_cast<std::chrono::milliseconds>(
        context->deadline() - std::chrono::system_clock::now() - std::chrono::milliseconds(500));
    // A worker this server does not know (it restarted since the worker registered) is told at once,
    // not after a long poll, so its devices are listed again within a second of its first call.
    const bool unknown = !workers_.Registered(request->worker_id());
    const auto deadline =
        Clock::now() + (unknown ? std::chrono::milliseconds(0)
                                : std::max(std::chrono::milliseconds(0), std::min(wait, caller_left)));
    auto granted = coordinator_.Lease(
        request->worker_id(), deadline, ServedTenant(call.caller),
        [context] { return context->IsCancelled(); }, TokenOf(call.caller));
    response->set_register_again(unknown);
    if (!granted) return grpc::Status::OK;
    call.wrote = true;
    call.job_id = granted->job.id();
    const auto release = [&](const std::string& reason) {  // the job back to the queue, uncounted
      v1::FailRequest request;
      request.set_lease_id(granted->lease_id);
      request.set_retry(true);
      request.set_release(true);
      request.set_reason(reason);
      coordinator_.Fail(request);
    };
    if (context->IsCancelled()) {
      release("the lease call was cancelled before the worker got the job");
      return grpc::Status(grpc::StatusCode::CANCELLED, "lease call cancelled");
    }
    // Admitted again once there is a job to give: tokens created, or the caller's revoked, while the
    // call waited gave the job to a worker that could not report on it; the job waited a lease's time
    // and lost an attempt (found 2026-12-07).
    try {
      guard_.Admit(*context, rpc, call);
    } catch (const Error& e) {
      release(std::string("the worker's lease call was refused before it got the job: ") + e.what());
      throw;
    }
    *response->mutable_job() = std::move(granted->job);
    response->set_lease_id(granted->lease_id);
    response->set_attempt(granted->attempt);
    return grpc::Status::OK;
  });
}

grpc::Status WorkerServiceImpl::Report(
    grpc::ServerContext* context, grpc::ServerReaderWriter<v1::ProgressReply, v1::ProgressUpdate>* stream) {
  const Rpc rpc{"Report", Access::kWorker, kWrites, ""};
  return guard_.Run(context, rpc, [&](Call& call) {
    v1::ProgressUpdate update;
    auto admitted = std::chrono::steady_clock::now();
    while (stream->Read(&update)) {
      // A stream lives up to an hour: the worker's token is checked again every 10 s, so one revoked
      // or expired meanwhile stops renewing the lease (the worker reopens with its current token).
      if (std::chrono::steady_clock::now() - admitted > std::chrono::seconds(10)) {
        guard_.Admit(*context, rpc, call);
        admitted = std::chrono::steady_clock::now();
      }
      if (update.has_progress()) {
        update.mutable_progress()->set_phase(PrintableText(update.progress().phase(), 64));
      }
      v1::ProgressReply reply;
      bool register_again = false;
      reply.set_action(coordinator_.Report(update, TokenOf(call.caller), &call.job_id, &register_again,
                                           ServedTenant(call.caller)));
      reply.set_register_again(register_again);
      if (!stream->Write(reply) || reply.action() != v1::ProgressReply::CONTINUE) break;
    }
    return grpc::Status::OK;
  });
}

grpc::Status WorkerServiceImpl::Complete(grpc::ServerContext* context, const v1::CompleteRequest* request,
                                         v1::Job* job) {
  return guard_.Run(context, {"Complete", Access::kWorker, kWrites, ""}, [&](Call& call) {
    *job = coordinator_.Complete(*request, ServedTenant(call.caller), &call.job_id);
    return grpc::Status::OK;
  });
}

grpc::Status WorkerServiceImpl::Fail(grpc::ServerContext* context, const v1::FailRequest* request,
                                     v1::Job* job) {
  return guard_.Run(context, {"Fail", Access::kWorker, kWrites, ""}, [&](Call& call) {
    // The reason reaches `status`, `watch` and the logs: printable (a worker's "\x1b]0;...\n FAKE:
    // job SUCCEEDED" was printed as it came; found 2026-12-06).
    v1::FailRequest failed = *request;
    failed.set_reason(PrintableText(failed.reason(), kMaxFailureReasonBytes));
    *job = coordinator_.Fail(failed);
    call.job_id = job->id();
    return grpc::Status::OK;
  });
}

grpc::Status WorkerServiceImpl::QueryBlobs(grpc::ServerContext* context, const v1::Manifest* manifest,
                                           v1::UploadStatus* status) {
  return guard_.Run(context, {"QueryBlobs", Access::kWorker, kReads, ""}, [&](Call& call) {
    *status = uploads_.Query(*manifest, Uploader::kWorker,
                             coordinator_.WorkerUploadOwner(ServedTenant(call.caller)));
    return grpc::Status::OK;
  });
}

grpc::Status WorkerServiceImpl::PutBlobs(grpc::ServerContext* context,
                                         grpc::ServerReader<v1::UploadRequest>* reader,
                                         v1::UploadStatus* status) {
  return guard_.Run(context, {"PutBlobs", Access::kWorker, kWrites, ""}, [&](Call& call) {
    *status = uploads_.Receive(
        *reader, Uploader::kWorker, coordinator_.WorkerUploadOwner(ServedTenant(call.caller)), {},
        [&](const std::function<bool()>& read) { return stalls_.Guard(context, read); },
        [context] { return context->IsCancelled(); });
    return grpc::Status::OK;
  });
}

grpc::Status WorkerServiceImpl::GetBlobs(grpc::ServerContext* context, const v1::GetBlobsRequest* request,
                                         grpc::ServerWriter<v1::FileChunk>* writer) {
  return guard_.Run(context, {"GetBlobs", Access::kWorker, kReads, ""}, [&](Call& call) {
    const auto job = coordinator_.CheckLease(request->lease_id());
    call.job_id = job.id();
    // A lease opens its own job's clip and checkpoint, not every blob of every tenant; each at the
    // size the job declares (SendFiles sets a stored copy of another size aside as damaged).
    std::map<std::string, std::int64_t> allowed{{job.checkpoint().sha256(), job.checkpoint().size()}};
    for (const auto& file : job.clip().files()) allowed[file.sha256()] = file.size();
    std::vector<std::pair<v1::FileEntry, std::int64_t>> files;
    for (const auto& range : request->files()) {
      const auto found = range.sha256().empty() ? allowed.end() : allowed.find(range.sha256());
      if (found == allowed.end())
        endorecon::Fail(ErrorCode::kNotFound,
                        "job " + job.id() + " has no file with sha256 '" + range.sha256() + "'");
      v1::FileEntry entry;
      entry.set_path(range.path());
      entry.set_sha256(range.sha256());
      entry.set_size(found->second);
      files.emplace_back(entry, range.offset());
    }
    try {
      metrics_.DownloadBytes(SendFiles(blobs_, files, *writer, stalls_, context));
    } catch (const Error& e) {
      if (e.code() != ErrorCode::kDataLoss && e.code() != ErrorCode::kNotFound) throw;
      // The server's copy of the job's file is damaged and set aside (DATA_LOSS), or gone (set aside
      // while another job of the same content ran): no attempt can succeed, and three did, each
      // refused (found 2026-12-06). The job fails saying what to do; a submit of the clip uploads the
      // file anew.
      const std::string why =
          e.code() == ErrorCode::kDataLoss
              ? std::string(e.what())
              : "a file of the job is no longer in the server's store: " + std::string(e.what()) +
                    " (set aside as damaged, or left out of a restore: the server's log says which)";
      // The operator's side of it, in the server's log (a missing file was said to the user alone).
      spdlog::error("job {}: {}", job.id(), why);
      v1::FailRequest failed;
      failed.set_lease_id(request->lease_id());
      failed.set_retry(false);
      failed.set_reason(why + ": submit the clip again");
      coordinator_.Fail(failed);
      throw;
    }
    return grpc::Status::OK;
  });
}

}  // namespace endorecon::server
