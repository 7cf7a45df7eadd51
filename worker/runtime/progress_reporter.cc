#include "worker/runtime/progress_reporter.h"

#include <spdlog/spdlog.h>

#include "common/transport_security.h"

namespace endorecon::worker {

ProgressReporter::ProgressReporter(WorkerClient& client, std::string lease_id,
                                   std::chrono::milliseconds interval, std::chrono::milliseconds lease_ttl)
    : client_(client),
      lease_id_(std::move(lease_id)),
      interval_(interval),
      lease_ttl_(lease_ttl),
      thread_([this] { Loop(); }) {}

ProgressReporter::~ProgressReporter() { Stop(); }

void ProgressReporter::SetProgress(const v1::Progress& progress) {
  std::lock_guard lock(mutex_);
  progress_ = progress;
}

void ProgressReporter::AddPreview(v1::Preview preview) {
  std::lock_guard lock(mutex_);
  previews_.push_back(std::move(preview));
}

void ProgressReporter::SetCheckpoint(const v1::FileEntry& checkpoint) {
  {
    std::lock_guard lock(mutex_);
    checkpoint_ = checkpoint;
  }
  wake_.notify_one();
}

std::optional<v1::ProgressReply::Action> ProgressReporter::stop_requested() const {
  std::lock_guard lock(mutex_);
  return stop_;
}

std::chrono::steady_clock::time_point ProgressReporter::last_answer() const {
  std::lock_guard lock(mutex_);
  return last_answer_;
}

void ProgressReporter::Stop() {
  {
    std::lock_guard lock(mutex_);
    if (stopping_) return;
    stopping_ = true;
  }
  wake_.notify_one();
  thread_.join();
}

bool ProgressReporter::SendPending() {
  std::vector<v1::ProgressUpdate> updates;
  {
    std::lock_guard lock(mutex_);
    auto& update = updates.emplace_back();
    update.set_lease_id(lease_id_);
    if (progress_) *update.mutable_progress() = *progress_;
    if (checkpoint_) *update.mutable_checkpoint() = *checkpoint_;
    for (auto& preview : previews_) {
      auto& with_preview = updates.emplace_back();
      with_preview.set_lease_id(lease_id_);
      *with_preview.mutable_preview() = std::move(preview);
    }
    progress_.reset();
    checkpoint_.reset();
    previews_.clear();
  }
  if (!stream_) {
    // Each stream has a deadline too; when it runs out the stream is simply reopened.
    context_ = CallContext(std::chrono::hours(1));
    stream_ = client_.OpenReport(context_.get());
  }
  for (const auto& update : updates) {
    v1::ProgressReply reply;
    if (!stream_->Write(update) || !stream_->Read(&reply)) {
      const auto status = stream_->Finish();
      if (int held = 0; stream_warnings_.Due(held)) {
        spdlog::warn("progress stream of lease {} broke ({}); reopening{}", lease_id_, status.error_message(),
                     held > 0 ? fmt::format(" ({} more breaks since the last warning)", held) : "");
      }
      stream_.reset();
      std::lock_guard lock(mutex_);  // keep what could not be sent for the next attempt
      if (update.has_checkpoint() && !checkpoint_) checkpoint_ = update.checkpoint();
      // Refused (the server is up) since before a lease would have expired: the job is no longer
      // this worker's. A worker whose token expired trained on, reporting every 2.5 s into the audit
      // log, while the server gave the job to another (found 2026-12-06).
      const bool refused = status.error_code() == grpc::StatusCode::UNAUTHENTICATED ||
                           status.error_code() == grpc::StatusCode::PERMISSION_DENIED;
      const auto silent = std::chrono::steady_clock::now() - last_answer_;
      if (refused && silent > lease_ttl_ + interval_) {
        spdlog::error(
            "the server has refused this worker's reports for {:.1f} s, longer than it keeps a lease ({:.1f} "
            "s): it "
            "has taken the job of lease {} back, so it stops here ({}; write a valid worker token into "
            "--token-file)",
            std::chrono::duration<double>(silent).count(), std::chrono::duration<double>(lease_ttl_).count(),
            lease_id_, status.error_message());
        stop_ = v1::ProgressReply::STOP_LEASE_LOST;
      }
      return false;
    }
    if (reply.register_again()) client_.RegisterAgain();
    std::lock_guard lock(mutex_);
    if (reply.action() != v1::ProgressReply::CONTINUE) {
      stop_ = reply.action();
      return true;
    }
    last_answer_ = std::chrono::steady_clock::now();
  }
  return true;
}

void ProgressReporter::Loop() {
  while (true) {
    bool stopping = false;
    {
      std::unique_lock lock(mutex_);
      wake_.wait_for(lock, interval_, [&] { return stopping_ || checkpoint_.has_value(); });
      stopping = stopping_;
      if (stop_) break;
    }
    const bool sent = SendPending();
    if (stopping || stop_requested()) break;
    if (!sent) client_.PauseBeforeRetry(std::chrono::milliseconds(500));
  }
  if (stream_) {
    stream_->WritesDone();
    stream_->Finish();
  }
}

}  // namespace endorecon::worker
