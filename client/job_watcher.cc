#include "client/job_watcher.h"

#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <set>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "client/interrupt_note.h"
#include "client/job_format.h"
#include "common/file_write.h"
#include "common/grpc_status.h"
#include "common/transport_security.h"

namespace endorecon::client {
namespace {

bool Terminal(v1::JobState state) {
  return state == v1::SUCCEEDED || state == v1::FAILED || state == v1::CANCELLED;
}

void SavePreview(const std::string& dir, const v1::Preview& preview) {
  // The kind comes from a worker through the server: one that is not a plain word (`../x`, `/x`)
  // would name a file outside `dir`.
  const std::string& kind = preview.kind();
  const bool word = !kind.empty() && kind.size() <= 32 && std::all_of(kind.begin(), kind.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_';
  });
  if (!word) return;
  const auto path =
      std::filesystem::path(dir) / (kind + "-it" + std::to_string(preview.iteration()) + ".png");
  WriteFile(path, preview.png(), "preview");
}

// Prints events as they come: on a terminal the progress line rewrites itself.
class EventPrinter {
 public:
  explicit EventPrinter(bool json) : json_(json), tty_(isatty(STDOUT_FILENO) != 0) {}

  void Job(const v1::Job& job) {
    if (json_) return Json(job);
    // The retrieval's and the sends' lines: only those that changed (the whole block was printed
    // again on every send's update).
    std::vector<std::string> dicom;
    std::istringstream lines(DicomLines(job));
    for (std::string line; std::getline(lines, line);) dicom.push_back(line);
    for (std::size_t i = 0; i < dicom.size(); ++i) {
      if (i < last_dicom_.size() && dicom[i] == last_dicom_[i]) continue;
      EndLine();
      std::cout << dicom[i] << "\n" << std::flush;
    }
    last_dicom_ = std::move(dicom);
    if (job.state() == last_state_) return;
    EndLine();
    last_state_ = job.state();
    std::cout << "job " << job.id() << " " << v1::JobState_Name(job.state());
    if (job.state() == v1::RUNNING) std::cout << " on " << job.worker_id();
    // An unfinished job's reason is why it was last requeued, as `status` labels it: "RUNNING on w2:
    // worker w1: shutting down" read as w2's (found 2026-12-07).
    if (!job.error().empty()) {
      if (Terminal(job.state()))
        std::cout << ": " << job.error();
      else
        std::cout << " (requeued: " << job.error() << ")";
    }
    if (const auto outcome = OutcomeLine(job); !outcome.empty()) std::cout << ": " << outcome;
    std::cout << std::endl;
  }
  void Progress(const v1::Progress& progress) {
    if (json_) return Json(progress);
    // A finished job's last progress ("evaluating the results: frame 8/8") is history: its outcome
    // line says how it ended (`send --wait` on a SUCCEEDED job printed it after that line).
    if (Terminal(last_state_)) return;
    if (tty_) {
      std::cout << "\r" << ProgressLine(progress) << "\033[K" << std::flush;
      open_line_ = true;
    } else {
      std::cout << ProgressLine(progress) << std::endl;
    }
  }
  void Preview(const v1::Preview& preview, const std::string& saved_to) {
    if (json_) return;
    EndLine();
    std::cout << "preview " << preview.kind() << " at iteration " << preview.iteration() << " saved in "
              << saved_to << std::endl;
  }
  void EndLine() {
    if (open_line_) std::cout << std::endl;
    open_line_ = false;
  }

 private:
  void Json(const google::protobuf::Message& message) {
    v1::JobEvent event;
    if (const auto* job = dynamic_cast<const v1::Job*>(&message)) *event.mutable_job() = *job;
    if (const auto* progress = dynamic_cast<const v1::Progress*>(&message))
      *event.mutable_progress() = *progress;
    std::cout << ToJson(event) << std::endl;
  }
  bool json_;
  bool tty_;
  bool open_line_ = false;
  v1::JobState last_state_ = v1::JOB_STATE_UNSPECIFIED;
  std::vector<std::string> last_dicom_;
};

}  // namespace

v1::Job WatchJob(const Globals& globals, const std::string& id, const WatchOptions& options) {
  const auto channel = globals.Channel();
  const auto stub = v1::JobService::NewStub(channel);
  EventPrinter printer(globals.json);
  // Ctrl-C ends the watch, not the job: a script that ran `submit --wait` again submitted the job twice
  // (found 2026-12-05).
  const InterruptNote interrupt_note("stopped watching; job " + id +
                                     " goes on on the server: `endorecon watch " + id +
                                     "` follows it again, `endorecon cancel " + id + "` stops it");
  v1::WatchJobRequest request;
  request.set_id(id);
  request.set_previews(!options.previews_dir.empty());
  // Previews are renders of the patient's frames: what the watch creates is the user's alone, as
  // fetch's results are. They followed the umask, 0644 (found 2026-12-07).
  if (!options.previews_dir.empty()) ::umask(077);
  auto unreachable_since = std::chrono::steady_clock::now();
  v1::Job job;
  // The previews saved, by kind and iteration: a stream opened again (each --timeout, or after a
  // server restart) starts with the latest preview, which was saved and said again (found 2026-12-07).
  std::set<std::pair<std::string, std::int64_t>> previews;
  while (true) {
    auto context = CallContext(std::chrono::milliseconds(static_cast<long>(options.stream_s * 1000)));
    auto reader = stub->Watch(context.get(), request);
    v1::JobEvent event;
    bool heard = false;
    while (reader->Read(&event)) {
      heard = true;
      if (event.has_progress()) printer.Progress(event.progress());
      if (event.has_preview() &&
          previews.emplace(event.preview().kind(), event.preview().iteration()).second) {
        SavePreview(options.previews_dir, event.preview());
        printer.Preview(event.preview(), options.previews_dir);
      }
      if (event.has_job()) {
        job = event.job();
        printer.Job(job);
      }
    }
    const auto status = reader->Finish();
    // The server answered this stream: it was reachable until the stream's end (its deadline, with
    // nothing new to say). Counted from the stream's last event, a job waiting longer than
    // --timeout for a worker failed the watch "Deadline Exceeded" (found 2026-12-07).
    if (heard) unreachable_since = std::chrono::steady_clock::now();
    if (status.ok() && Terminal(job.state())) break;
    const bool retry = status.ok() || status.error_code() == grpc::StatusCode::DEADLINE_EXCEEDED ||
                       status.error_code() == grpc::StatusCode::UNAVAILABLE;
    if (!retry) {
      printer.EndLine();
      ThrowIfFailed(status, "watch " + id);
    }
    if (std::chrono::steady_clock::now() - unreachable_since > globals.timeout()) {
      printer.EndLine();
      // The server away longer than --timeout: the job is not lost, and the user is told how to
      // follow it again (a Ctrl-C said so, a server away did not; found 2026-12-07).
      try {
        ThrowIfFailed(status, "watch " + id);
      } catch (const Error& e) {
        Fail(e.code(), std::string(e.what()) + "\nendorecon: stopped watching; job " + id +
                           " goes on on the server once it is back: `endorecon watch " + id +
                           "` follows it again");
      }
    }
    PauseBeforeRetry(*channel, std::chrono::milliseconds(500));  // a restarted server: as soon as it is back
  }
  printer.EndLine();
  // Said, not left to an empty folder (found 2026-12-07).
  if (!options.previews_dir.empty() && previews.empty() && !globals.json) {
    std::cerr << "endorecon: no preview arrived while watching, so nothing was saved in "
              << options.previews_dir
              << ": a worker sends one each --preview-interval of training (30 s by default) "
                 "and one of a prepared recording\n";
  }
  return job;
}

}  // namespace endorecon::client
