// Keeps a leased job's Report stream going on its own thread: every heartbeat interval it sends
// the latest progress, any new previews and the latest checkpoint, which also renews the lease,
// and reads the server's answer. When the server says stop (the job was cancelled, or the lease
// is lost) stop_requested() turns true and the engine's should_stop hook sees it. A broken stream
// (server restart) is reopened; the lease outlives it as long as the server comes back within
// the lease TTL. A server that refuses the worker's token (expired or revoked, not replaced) for
// longer than a lease lives has taken the job back: that is a stop too (STOP_LEASE_LOST).
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "common/warning_pacer.h"
#include "endorecon/v1/worker_service.pb.h"
#include "worker/runtime/worker_client.h"

namespace endorecon::worker {

class ProgressReporter {
 public:
  // `lease_ttl`: how long the server keeps a lease that is not renewed.
  ProgressReporter(WorkerClient& client, std::string lease_id, std::chrono::milliseconds interval,
                   std::chrono::milliseconds lease_ttl = std::chrono::seconds(30));
  ~ProgressReporter();  // Stop()s

  void SetProgress(const v1::Progress& progress);
  void AddPreview(v1::Preview preview);
  void SetCheckpoint(const v1::FileEntry& checkpoint);
  // Sends what is pending once more, then closes the stream and joins the thread.
  void Stop();

  // The server's reason to stop, once it gave one.
  std::optional<v1::ProgressReply::Action> stop_requested() const;
  // When the server last answered an update (the lease then held); the reporter's start before.
  std::chrono::steady_clock::time_point last_answer() const;

 private:
  void Loop();
  // Sends one update on the open stream (opening it if needed); false if the stream broke.
  bool SendPending();

  WorkerClient& client_;
  std::string lease_id_;
  std::chrono::milliseconds interval_;
  std::chrono::milliseconds lease_ttl_;
  mutable std::mutex mutex_;
  std::condition_variable wake_;
  std::optional<v1::Progress> progress_;
  std::vector<v1::Preview> previews_;
  std::optional<v1::FileEntry> checkpoint_;
  std::optional<v1::ProgressReply::Action> stop_;
  std::chrono::steady_clock::time_point last_answer_ = std::chrono::steady_clock::now();
  WarningPacer stream_warnings_;  // a broken stream is said once, then every 30 s
  bool stopping_ = false;
  std::unique_ptr<grpc::ClientContext> context_;
  std::unique_ptr<grpc::ClientReaderWriter<v1::ProgressUpdate, v1::ProgressReply>> stream_;
  std::thread thread_;
};

}  // namespace endorecon::worker
