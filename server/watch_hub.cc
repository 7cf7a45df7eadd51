#include "server/watch_hub.h"

#include <algorithm>

#include "server/job_states.h"

namespace endorecon::server {

std::shared_ptr<WatchHub::Entry> WatchHub::EntryOf(const std::string& job_id) {
  std::lock_guard lock(mutex_);
  auto& entry = entries_[job_id];
  if (!entry) entry = std::make_shared<Entry>();
  return entry;
}

template <typename Update>
void WatchHub::Publish(const std::string& job_id, Update&& update) {
  const auto entry = EntryOf(job_id);
  {
    std::lock_guard lock(entry->mutex);
    entry->version = ++last_version_;
    update(*entry, entry->version);
  }
  entry->published = true;
  entry->changed.notify_all();
}

void WatchHub::PublishJob(const v1::Job& job) {
  Publish(job.id(), [&](Entry& entry, std::uint64_t version) {
    entry.job = Versioned<v1::Job>{version, job};
    entry.job->value.clear_clip();
    entry.job->value.clear_result();
    if (Terminal(job.state())) entry.previews.clear();
    entry.settled_ns = Settled(job) ? std::chrono::steady_clock::now().time_since_epoch().count() : 0;
  });
}

void WatchHub::PublishProgress(const std::string& job_id, const v1::Progress& progress) {
  Publish(job_id, [&](Entry& entry, std::uint64_t version) {
    entry.progress = Versioned<v1::Progress>{version, progress};
  });
}

void WatchHub::PublishPreview(const std::string& job_id, const v1::Preview& preview) {
  Publish(job_id, [&](Entry& entry, std::uint64_t version) {
    entry.previews[preview.kind()] = Versioned<v1::Preview>{version, preview};
  });
}

WatchHub::Changes WatchHub::Wait(const std::string& job_id, std::uint64_t seen,
                                 std::chrono::steady_clock::time_point deadline) {
  const auto entry = EntryOf(job_id);
  Changes changes;
  std::unique_lock lock(entry->mutex);
  entry->changed.wait_until(lock, deadline, [&] {
    std::lock_guard hub_lock(mutex_);
    return shutdown_ || entry->version > seen;
  });
  changes.version = std::max(seen, entry->version);
  if (entry->version <= seen) return changes;
  if (entry->job && entry->job->version > seen) changes.job = entry->job->value;
  if (entry->progress && entry->progress->version > seen) changes.progress = entry->progress->value;
  for (const auto& [kind, preview] : entry->previews) {
    if (preview.version > seen) changes.previews.push_back(preview.value);
  }
  return changes;
}

std::size_t WatchHub::Prune(std::chrono::steady_clock::time_point now, std::chrono::seconds grace) {
  const auto cutoff = (now - grace).time_since_epoch().count();
  std::lock_guard lock(mutex_);
  std::size_t dropped = 0;
  for (auto it = entries_.begin(); it != entries_.end();) {
    // Under the hub's mutex nobody can take a new reference, so a count of 1 stays 1.
    const auto& entry = *it->second;
    const std::int64_t settled = entry.settled_ns;
    const bool done = settled != 0 && settled <= cutoff;
    if (it->second.use_count() == 1 && (done || !entry.published)) {
      it = entries_.erase(it);
      ++dropped;
    } else {
      ++it;
    }
  }
  return dropped;
}

std::size_t WatchHub::Size() {
  std::lock_guard lock(mutex_);
  return entries_.size();
}

void WatchHub::Shutdown() {
  std::lock_guard lock(mutex_);
  shutdown_ = true;
  for (auto& [id, entry] : entries_) entry->changed.notify_all();
}

}  // namespace endorecon::server
