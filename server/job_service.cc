#include "server/job_service.h"

#include <algorithm>
#include <map>

#include "common/error.h"
#include "common/grpc_status.h"
#include "server/file_sender.h"

namespace endorecon::server {
namespace {

bool Terminal(v1::JobState state) {
  return state == v1::SUCCEEDED || state == v1::FAILED || state == v1::CANCELLED;
}

// A watch ends when nothing more will happen to the job: it is finished and none of its DICOM
// sends is still waiting for an attempt or in one.
bool Settled(const v1::Job& job) {
  if (!Terminal(job.state())) return false;
  if (job.state() != v1::SUCCEEDED) return true;
  return std::none_of(job.sends().begin(), job.sends().end(), [](const v1::DicomSend& send) {
    return send.state() == v1::DicomSend::PENDING || send.state() == v1::DicomSend::SENDING;
  });
}

}  // namespace

JobServiceImpl::JobServiceImpl(JobCoordinator& coordinator, UploadReceiver& uploads, BlobStore& blobs,
                               WatchHub& hub, WorkerRegistry& workers, Metrics& metrics)
    : coordinator_(coordinator),
      uploads_(uploads),
      blobs_(blobs),
      hub_(hub),
      workers_(workers),
      metrics_(metrics) {}

grpc::Status JobServiceImpl::QueryUpload(grpc::ServerContext*, const v1::Manifest* manifest,
                                         v1::UploadStatus* status) {
  return GuardStatus([&] {
    *status = uploads_.Query(*manifest);
    return grpc::Status::OK;
  });
}

grpc::Status JobServiceImpl::Upload(grpc::ServerContext*, grpc::ServerReader<v1::UploadRequest>* reader,
                                    v1::UploadStatus* status) {
  return GuardStatus([&] {
    *status = uploads_.Receive(*reader);
    return grpc::Status::OK;
  });
}

grpc::Status JobServiceImpl::Submit(grpc::ServerContext*, const v1::SubmitRequest* request, v1::Job* job) {
  return GuardStatus([&] {
    *job = coordinator_.Submit(*request);
    return grpc::Status::OK;
  });
}

grpc::Status JobServiceImpl::Get(grpc::ServerContext*, const v1::GetJobRequest* request, v1::Job* job) {
  return GuardStatus([&] {
    *job = coordinator_.Get(request->id());
    return grpc::Status::OK;
  });
}

grpc::Status JobServiceImpl::List(grpc::ServerContext*, const v1::ListJobsRequest* request,
                                  v1::ListJobsResponse* response) {
  return GuardStatus([&] {
    const int size = request->page_size() <= 0 ? 50 : std::min(request->page_size(), 1000);
    std::int64_t before = 0;
    if (!request->page_token().empty()) {
      try {
        before = std::stoll(request->page_token());
      } catch (const std::exception&) {
        FailInvalid("page_token '" + request->page_token() + "' is not one this server returned");
      }
    }
    std::vector<v1::JobState> states;
    for (const int state : request->states()) states.push_back(static_cast<v1::JobState>(state));
    const auto page = coordinator_.List(states, size, before);
    for (auto job : page.jobs) {
      job.clear_clip();
      job.clear_result();
      *response->add_jobs() = std::move(job);
    }
    if (page.next_before_seq > 0) response->set_next_page_token(std::to_string(page.next_before_seq));
    return grpc::Status::OK;
  });
}

grpc::Status JobServiceImpl::Cancel(grpc::ServerContext*, const v1::CancelJobRequest* request, v1::Job* job) {
  return GuardStatus([&] {
    *job = coordinator_.Cancel(request->id());
    return grpc::Status::OK;
  });
}

grpc::Status JobServiceImpl::Watch(grpc::ServerContext* context, const v1::WatchJobRequest* request,
                                   grpc::ServerWriter<v1::JobEvent>* writer) {
  return GuardStatus([&] {
    v1::JobEvent first;
    *first.mutable_job() = coordinator_.Get(request->id());
    first.mutable_job()->clear_clip();
    if (!writer->Write(first) || Settled(first.job())) return grpc::Status::OK;
    std::uint64_t seen = 0;
    while (!context->IsCancelled()) {
      auto changes =
          hub_.Wait(request->id(), seen, std::chrono::steady_clock::now() + std::chrono::seconds(1));
      seen = changes.version;
      std::vector<v1::JobEvent> events;
      if (changes.progress) *events.emplace_back().mutable_progress() = *changes.progress;
      if (request->previews()) {
        for (auto& preview : changes.previews) *events.emplace_back().mutable_preview() = std::move(preview);
      }
      if (changes.job) *events.emplace_back().mutable_job() = *changes.job;
      for (const auto& event : events) {
        if (!writer->Write(event)) return grpc::Status::OK;
      }
      if (changes.job && Settled(*changes.job)) return grpc::Status::OK;
    }
    return grpc::Status(grpc::StatusCode::CANCELLED, "watch cancelled");
  });
}

grpc::Status JobServiceImpl::Fetch(grpc::ServerContext*, const v1::FetchRequest* request,
                                   grpc::ServerWriter<v1::FileChunk>* writer) {
  return GuardStatus([&] {
    const auto job = coordinator_.Get(request->id());
    if (job.state() != v1::SUCCEEDED) {
      Fail(ErrorCode::kFailedPrecondition, "job " + job.id() + " is " + v1::JobState_Name(job.state()) +
                                               "; results exist once it has SUCCEEDED");
    }
    std::map<std::string, v1::FileEntry> by_path;
    for (const auto& entry : job.result().files()) by_path[entry.path()] = entry;
    std::vector<std::pair<v1::FileEntry, std::int64_t>> files;
    if (request->files().empty()) {
      for (const auto& entry : job.result().files()) files.emplace_back(entry, 0);
    }
    for (const auto& range : request->files()) {
      const auto found = by_path.find(range.path());
      if (found == by_path.end())
        Fail(ErrorCode::kNotFound, "job " + job.id() + " has no result '" + range.path() + "'");
      files.emplace_back(found->second, range.offset());
    }
    metrics_.DownloadBytes(SendFiles(blobs_, files, *writer));
    return grpc::Status::OK;
  });
}

grpc::Status JobServiceImpl::ListWorkers(grpc::ServerContext*, const v1::ListWorkersRequest*,
                                         v1::ListWorkersResponse* response) {
  for (auto& worker : workers_.List()) *response->add_workers() = std::move(worker);
  return grpc::Status::OK;
}

grpc::Status JobServiceImpl::Send(grpc::ServerContext*, const v1::SendRequest* request, v1::Job* job) {
  return GuardStatus([&] {
    *job = coordinator_.RequestSend(request->id(), request->destination());
    job->clear_clip();
    return grpc::Status::OK;
  });
}

}  // namespace endorecon::server
