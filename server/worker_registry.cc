#include "server/worker_registry.h"

#include <spdlog/spdlog.h>

#include <utility>

#include "common/error.h"
#include "server/drain_file.h"
#include "server/unix_time.h"

namespace endorecon::server {

WorkerRegistry::WorkerRegistry(std::chrono::milliseconds alive_window, std::filesystem::path drains_file)
    : alive_window_(alive_window), drains_file_(std::move(drains_file)) {
  if (drains_file_.empty()) return;
  Drains drains;
  try {
    drains = ReadDrains(drains_file_);
  } catch (const Error& e) {
    spdlog::warn("{}; no worker starts drained (drain them again with `endorecon drain WORKER`)", e.what());
  }
  for (const auto& [id, seen] : drains) {
    auto& entry = workers_[id];
    entry.info.set_id(id);
    entry.info.set_last_seen_unix_ms(seen);
    entry.info.set_draining(true);
    entry.last_seen = NotAliveSince();
  }
  if (!drains.empty()) spdlog::info("{} worker(s) drained before the restart still drain", drains.size());
}

void WorkerRegistry::SaveDrains() const {
  if (drains_file_.empty()) return;
  Drains drains;
  for (const auto& [id, entry] : workers_) {
    if (entry.info.draining()) drains[id] = entry.info.last_seen_unix_ms();
  }
  WriteDrains(drains_file_, drains);
}

void WorkerRegistry::SaveDrainsOrWarn() const {
  try {
    SaveDrains();
  } catch (const Error& e) {
    spdlog::warn("drained workers: {}", e.what());
  }
}

WorkerRegistry::Entry& WorkerRegistry::At(const std::string& worker_id) {
  auto& entry = workers_[worker_id];
  entry.info.set_id(worker_id);
  if (entry.left) return entry;
  entry.info.set_last_seen_unix_ms(NowUnixMs());
  entry.last_seen = std::chrono::steady_clock::now();
  return entry;
}

std::string WorkerRegistry::Register(const v1::RegisterRequest& request, const std::string& principal,
                                     const std::string& tenant) {
  std::lock_guard lock(mutex_);
  std::string before;
  if (const auto found = workers_.find(request.worker_id());
      found != workers_.end() && found->second.registered && found->second.principal != principal &&
      std::chrono::steady_clock::now() - found->second.last_seen <= alive_window_) {
    before = found->second.principal;
  }
  workers_[request.worker_id()].left = false;
  auto& entry = At(request.worker_id());
  entry.registered = true;
  entry.principal = principal;
  entry.info.set_hostname(request.hostname());
  entry.info.set_version(request.version());
  *entry.info.mutable_devices() = request.devices();
  *entry.info.mutable_device_info() = request.device_info();
  entry.info.set_tenant(tenant);
  if (!request.again() && entry.info.draining()) {
    entry.info.set_draining(false);  // a restarted worker serves again
    SaveDrainsOrWarn();
  }
  return before;
}

v1::WorkerInfo WorkerRegistry::SetDraining(const std::string& worker_id, bool draining) {
  std::lock_guard lock(mutex_);
  const auto found = workers_.find(worker_id);
  if (found == workers_.end()) {
    std::string known;
    int named = 0;
    for (const auto& [id, entry] : workers_) {
      if (named++ == 10) {
        known += ", ...";
        break;
      }
      known += (known.empty() ? "" : ", ") + id;
    }
    Fail(ErrorCode::kNotFound, "no worker '" + worker_id + "' (known: " + (known.empty() ? "none" : known) +
                                   "; `endorecon workers` lists them)");
  }
  const bool was = found->second.info.draining();
  found->second.info.set_draining(draining);
  if (was != draining) {
    try {
      SaveDrains();
    } catch (...) {
      found->second.info.set_draining(was);
      throw;
    }
  }
  return InfoOf(found->second, std::chrono::steady_clock::now());
}

bool WorkerRegistry::Draining(const std::string& worker_id) const {
  std::lock_guard lock(mutex_);
  const auto found = workers_.find(worker_id);
  return found != workers_.end() && found->second.info.draining();
}

bool WorkerRegistry::Registered(const std::string& worker_id) const {
  std::lock_guard lock(mutex_);
  const auto found = workers_.find(worker_id);
  return found != workers_.end() && found->second.registered;
}

void WorkerRegistry::Touch(const std::string& worker_id) {
  std::lock_guard lock(mutex_);
  At(worker_id);
}

std::string WorkerRegistry::NoteToken(const std::string& worker_id, const std::string& principal,
                                      const std::string& tenant) {
  std::lock_guard lock(mutex_);
  const auto found = workers_.find(worker_id);
  if (found == workers_.end() || !found->second.registered) return "";
  // Listed with the tenant its calls carry now: a token of another scope written into a worker's
  // --token-file changed the jobs it ran, and `workers` went on showing the old scope.
  found->second.info.set_tenant(tenant);
  if (found->second.principal == principal) return "";
  return std::exchange(found->second.principal, principal);
}

void WorkerRegistry::Leave(const std::string& worker_id) {
  std::lock_guard lock(mutex_);
  if (const auto found = workers_.find(worker_id); found != workers_.end()) {
    found->second.last_seen = NotAliveSince();
    found->second.left = true;
  }
}

void WorkerRegistry::AddJob(const std::string& worker_id, const std::string& job_id) {
  std::lock_guard lock(mutex_);
  At(worker_id).jobs.insert(job_id);
}

void WorkerRegistry::RemoveJob(const std::string& worker_id, const std::string& job_id) {
  std::lock_guard lock(mutex_);
  if (const auto found = workers_.find(worker_id); found != workers_.end()) found->second.jobs.erase(job_id);
}

std::vector<v1::WorkerInfo> WorkerRegistry::List() const {
  std::lock_guard lock(mutex_);
  const auto now = std::chrono::steady_clock::now();
  std::vector<v1::WorkerInfo> list;
  for (const auto& [id, entry] : workers_) list.push_back(InfoOf(entry, now));
  return list;
}

v1::WorkerInfo WorkerRegistry::InfoOf(const Entry& entry, std::chrono::steady_clock::time_point now) const {
  v1::WorkerInfo info = entry.info;
  info.set_alive(now - entry.last_seen <= alive_window_);
  for (const auto& job : entry.jobs) info.add_job_ids(job);
  return info;
}

std::size_t WorkerRegistry::Forget(std::chrono::steady_clock::time_point cutoff) {
  std::lock_guard lock(mutex_);
  bool drained = false;
  const std::size_t forgotten = std::erase_if(workers_, [&](const auto& item) {
    const bool gone = item.second.last_seen < cutoff && item.second.jobs.empty();
    drained |= gone && item.second.info.draining();
    return gone;
  });
  if (drained) SaveDrainsOrWarn();
  return forgotten;
}

int WorkerRegistry::CountAlive() const {
  std::lock_guard lock(mutex_);
  const auto now = std::chrono::steady_clock::now();
  int alive = 0;
  for (const auto& [id, entry] : workers_) alive += now - entry.last_seen <= alive_window_ ? 1 : 0;
  return alive;
}

}  // namespace endorecon::server
