#include "server/job_service.h"

#include <fmt/chrono.h>
#include <spdlog/spdlog.h>

#include <map>

#include "common/error.h"
#include "common/job_bounds.h"
#include "common/job_results_text.h"
#include "server/file_sender.h"
#include "server/job_states.h"

namespace endorecon::server {

JobServiceImpl::JobServiceImpl(CallGuard& guard, JobCoordinator& coordinator, UploadReceiver& uploads,
                               BlobStore& blobs, WatchHub& hub, WorkerRegistry& workers, Metrics& metrics,
                               StallWatch& stalls)
    : guard_(guard),
      coordinator_(coordinator),
      uploads_(uploads),
      blobs_(blobs),
      hub_(hub),
      workers_(workers),
      metrics_(metrics),
      stalls_(stalls) {}

grpc::Status JobServiceImpl::QueryUpload(grpc::ServerContext* context, const v1::Manifest* manifest,
                                         v1::UploadStatus* status) {
  return guard_.Run(context, {"QueryUpload", Access::kJobs, kReads, ""}, [&](Call& call) {
    *status = uploads_.Query(*manifest, Uploader::kClient, coordinator_.ClientUploadOwner(call.caller));
    coordinator_.CheckUploadQuota(*manifest, call.caller);
    return grpc::Status::OK;
  });
}

grpc::Status JobServiceImpl::Upload(grpc::ServerContext* context,
                                    grpc::ServerReader<v1::UploadRequest>* reader, v1::UploadStatus* status) {
  return guard_.Run(context, {"Upload", Access::kJobs, kWrites, ""}, [&](Call& call) {
    *status = uploads_.Receive(
        *reader, Uploader::kClient, coordinator_.ClientUploadOwner(call.caller),
        [&](const v1::Manifest& manifest) { coordinator_.AdmitUpload(manifest, call.caller); },
        [&](const std::function<bool()>& read) { return stalls_.Guard(context, read); },
        [context] { return context->IsCancelled(); });
    // An upload its client gave up (Ctrl-C, a lost connection) was audited OK, like a whole one
    // (found 2026-12-06): CANCELLED says it did not finish.
    if (context->IsCancelled()) {
      return grpc::Status(
          grpc::StatusCode::CANCELLED,
          "the client went away during the upload; what arrived is kept for a resumed upload");
    }
    return grpc::Status::OK;
  });
}

namespace {

// What a client is shown of a job: not its lease id, a running worker's handle on it (the worker API
// needs a worker token and, with --tls-client-ca, a certificate, but a client has no use for it).
v1::Job ForClient(v1::Job job) {
  job.clear_lease_id();
  return job;
}

}  // namespace

grpc::Status JobServiceImpl::Submit(grpc::ServerContext* context, const v1::SubmitRequest* request,
                                    v1::Job* job) {
  // A check before an upload is audited apart: it queues nothing.
  const char* method = request->validate_only() ? "SubmitCheck" : "Submit";
  return guard_.Run(context, {method, Access::kJobs, kWrites, ""}, [&](Call& call) {
    *job = ForClient(coordinator_.Submit(*request, call.caller));
    call.job_id = job->id();
    return grpc::Status::OK;
  });
}

grpc::Status JobServiceImpl::Get(grpc::ServerContext* context, const v1::GetJobRequest* request,
                                 v1::Job* job) {
  return guard_.Run(context, {"Get", Access::kJobs, kReads, request->id()}, [&](Call& call) {
    *job = ForClient(coordinator_.Get(request->id(), call.caller));
    return grpc::Status::OK;
  });
}

grpc::Status JobServiceImpl::List(grpc::ServerContext* context, const v1::ListJobsRequest* request,
                                  v1::ListJobsResponse* response) {
  return guard_.Run(context, {"List", Access::kJobs, kReads, ""}, [&](Call& call) {
    const int size = request->page_size() <= 0 ? 50 : std::min(request->page_size(), 1000);
    std::vector<v1::JobState> states;
    for (const int state : request->states()) states.push_back(static_cast<v1::JobState>(state));
    const auto page = coordinator_.List(states, size, request->page_token(), call.caller);
    for (auto job : page.jobs) {
      job.clear_clip();
      job.clear_result();
      *response->add_jobs() = ForClient(std::move(job));
    }
    // The next page starts after the last job of this one: its id, not its place in the server's one
    // sequence, which told any tenant how many jobs all had submitted (found 2026-12-06).
    if (page.next_before_seq > 0 && !page.jobs.empty()) response->set_next_page_token(page.jobs.back().id());
    return grpc::Status::OK;
  });
}

grpc::Status JobServiceImpl::Cancel(grpc::ServerContext* context, const v1::CancelJobRequest* request,
                                    v1::Job* job) {
  return guard_.Run(context, {"Cancel", Access::kJobs, kWrites, request->id()}, [&](Call& call) {
    *job = ForClient(coordinator_.Cancel(request->id(), call.caller));
    return grpc::Status::OK;
  });
}

grpc::Status JobServiceImpl::Delete(grpc::ServerContext* context, const v1::DeleteJobRequest* request,
                                    v1::Job* job) {
  return guard_.Run(context, {"Delete", Access::kJobs, kWrites, request->id()}, [&](Call& call) {
    *job = ForClient(coordinator_.Delete(request->id(), call.caller));
    return grpc::Status::OK;
  });
}

grpc::Status JobServiceImpl::Watch(grpc::ServerContext* context, const v1::WatchJobRequest* request,
                                   grpc::ServerWriter<v1::JobEvent>* writer) {
  return guard_.Run(context, {"Watch", Access::kJobs, kReads, request->id()}, [&](Call& call) {
    v1::JobEvent first;
    *first.mutable_job() = ForClient(coordinator_.Get(request->id(), call.caller));
    first.mutable_job()->clear_clip();
    const auto write = [&](const v1::JobEvent& event) {
      return stalls_.Guard(context, [&] { return writer->Write(event); });
    };
    if (!write(first) || Settled(first.job())) return grpc::Status::OK;
    // The hub's first answer holds the job as last published, mostly what `first` already said: a
    // snapshot equal to the one sent last is not sent again.
    std::string last_sent = first.job().SerializeAsString();
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
      if (changes.job) {
        // The hub's copy has no result manifest; a settled job's last event has it, read from the
        // store, so `submit --wait --json` ends with the files it can fetch (found 2026-12-05).
        v1::Job job =
            ForClient(Settled(*changes.job) ? coordinator_.Get(request->id(), call.caller) : *changes.job);
        job.clear_clip();
        if (std::string bytes = job.SerializeAsString(); bytes != last_sent) {
          last_sent = std::move(bytes);
          *events.emplace_back().mutable_job() = std::move(job);
        }
      }
      if (events.empty()) {
        // A quiet second: the hub drops a settled job's entry a minute after it settled, so ask the
        // store whether this one settled meanwhile.
        v1::JobEvent last;
        *last.mutable_job() = ForClient(coordinator_.Get(request->id(), call.caller));
        if (Settled(last.job())) {
          last.mutable_job()->clear_clip();
          write(last);
          return grpc::Status::OK;
        }
      }
      for (const auto& event : events) {
        if (!write(event)) return grpc::Status::OK;
      }
      if (changes.job && Settled(*changes.job)) return grpc::Status::OK;
    }
    return grpc::Status(grpc::StatusCode::CANCELLED, "watch cancelled");
  });
}

grpc::Status JobServiceImpl::Fetch(grpc::ServerContext* context, const v1::FetchRequest* request,
                                   grpc::ServerWriter<v1::FileChunk>* writer) {
  return guard_.Run(context, {"Fetch", Access::kJobs, kReads, request->id()}, [&](Call& call) {
    const auto job = coordinator_.Get(request->id(), call.caller);
    const auto refuse_expired = [](const v1::Job& expired) {
      Fail(
          ErrorCode::kFailedPrecondition,
          fmt::format("job {} expired: its clip and results were deleted (retention, or a delete) on "
                      "{:%Y-%m-%d %H:%M} UTC",
                      expired.id(), fmt::gmtime(static_cast<std::time_t>(expired.expired_unix_ms() / 1000))));
    };
    if (job.expired_unix_ms() > 0) refuse_expired(job);
    if (job.state() != v1::SUCCEEDED) {
      Fail(ErrorCode::kFailedPrecondition, NoResultsYet(job, "fetched"));
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
    try {
      metrics_.DownloadBytes(SendFiles(blobs_, files, *writer, stalls_, context));
    } catch (const Error& e) {
      // Retention may delete the results while they are sent: say so, not "no blob with sha256 ...".
      if (e.code() != ErrorCode::kNotFound) throw;
      const auto now = coordinator_.Get(request->id(), call.caller);
      if (now.expired_unix_ms() > 0) refuse_expired(now);
      // A result set aside as damaged is that, not a missing job (a script read exit 3 as "no such
      // job" on the fetch after the one that found the damage; found 2026-12-06).
      for (const auto& [entry, offset] : files) {
        if (!blobs_.Has(entry.sha256()) && blobs_.WasSetAside(entry.sha256())) {
          Fail(ErrorCode::kDataLoss, "job " + job.id() + ": the server's stored copy of its result '" +
                                         entry.path() +
                                         "' was found damaged and set aside (a disk fault?): its results "
                                         "cannot be fetched whole; submit its clip again to make them anew");
        }
      }
      // Said in the server's log too: the operator restores it (a restore without it, the likely cause).
      spdlog::error("job {}: a result file is missing from the store: {}", job.id(), e.what());
      Fail(ErrorCode::kNotFound, "job " + job.id() + ": a result file is missing from the server's store: " +
                                     e.what() + " (tell the server's admin: its log names it)");
    }
    return grpc::Status::OK;
  });
}

grpc::Status JobServiceImpl::ListWorkers(grpc::ServerContext* context, const v1::ListWorkersRequest*,
                                         v1::ListWorkersResponse* response) {
  return guard_.Run(context, {"ListWorkers", Access::kAdmin, kReads, ""}, [&](Call&) {
    for (auto& worker : workers_.List()) *response->add_workers() = std::move(worker);
    return grpc::Status::OK;
  });
}

grpc::Status JobServiceImpl::Drain(grpc::ServerContext* context, const v1::DrainRequest* request,
                                   v1::WorkerInfo* worker) {
  // Audited apart: "Drain" and its undo read alike in the log (found 2026-12-06).
  const char* method = request->undo() ? "DrainUndo" : "Drain";
  return guard_.Run(context, {method, Access::kAdmin, kWrites, "", request->worker_id()}, [&](Call& call) {
    *worker = workers_.SetDraining(request->worker_id(), !request->undo());
    spdlog::info("worker {} {} by request of {}", request->worker_id(),
                 request->undo() ? "serves again (drain undone)" : "drains: it is given no new job",
                 call.caller.name);
    return grpc::Status::OK;
  });
}

grpc::Status JobServiceImpl::Uploads(grpc::ServerContext* context, const v1::UploadsRequest* request,
                                     v1::UploadsResponse* response) {
  // A drop deletes files: audited as a write, naming the tenant an admin asked for.
  const Rpc rpc{request->drop() ? "DropUploads" : "ListUploads", Access::kJobs, request->drop(), "",
                PrintableText(request->tenant(), 64)};
  return guard_.Run(context, rpc, [&](Call& call) {
    *response = coordinator_.Uploads(*request, call.caller);
    return grpc::Status::OK;
  });
}

grpc::Status JobServiceImpl::Send(grpc::ServerContext* context, const v1::SendRequest* request,
                                  v1::Job* job) {
  return guard_.Run(context, {"Send", Access::kJobs, kWrites, request->id()}, [&](Call& call) {
    *job = ForClient(coordinator_.RequestSend(request->id(), request->destination(), call.caller));
    job->clear_clip();
    return grpc::Status::OK;
  });
}

}  // namespace endorecon::server
