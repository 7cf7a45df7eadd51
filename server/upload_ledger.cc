#include "server/upload_ledger.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <nlohmann/json.hpp>
#include <set>

#include "common/error.h"
#include "common/file_write.h"
#include "common/json_file.h"
#include "server/unix_time.h"

namespace endorecon::server {

std::int64_t UploadLedger::PendingBytes(const std::string& tenant, const v1::Manifest& except) const {
  const auto found = tenants_.find(tenant);
  if (found == tenants_.end()) return 0;
  std::set<std::string> left_out;
  for (const auto& file : except.files()) left_out.insert(file.sha256());
  std::int64_t bytes = 0;
  for (const auto& [digest, entry] : found->second) {
    if (!left_out.count(digest)) bytes += entry.bytes;
  }
  return bytes;
}

std::int64_t UploadLedger::LastNotedUnixMs(const std::string& tenant) const {
  const auto found = tenants_.find(tenant);
  if (found == tenants_.end()) return 0;
  std::int64_t last = 0;
  for (const auto& [digest, entry] : found->second) last = std::max(last, entry.noted_unix_ms);
  return last;
}

bool UploadLedger::Add(const std::string& tenant, const v1::FileEntry& file, Time now) {
  if (file.sha256().empty()) return false;  // a sizes-only listing brings nothing yet
  tenants_[tenant][file.sha256()] = {file.size(), now, NowUnixMs()};
  return true;
}

void UploadLedger::Submitted(const std::string& tenant, const v1::Manifest& manifest) {
  const auto found = tenants_.find(tenant);
  if (found == tenants_.end()) return;
  std::size_t erased = 0;
  for (const auto& file : manifest.files()) erased += found->second.erase(file.sha256());
  if (found->second.empty()) tenants_.erase(found);
  if (erased > 0) Save();
}

std::size_t UploadLedger::ForgetBefore(Time cutoff) {
  std::size_t forgotten = 0;
  for (auto tenant = tenants_.begin(); tenant != tenants_.end();) {
    auto& files = tenant->second;
    forgotten += std::erase_if(files, [cutoff](const auto& item) { return item.second.noted < cutoff; });
    tenant = files.empty() ? tenants_.erase(tenant) : std::next(tenant);
  }
  if (forgotten > 0) Save();
  return forgotten;
}

void UploadLedger::KeepIn(const std::filesystem::path& file) {
  file_ = file;
  std::error_code error;
  if (!std::filesystem::exists(file, error)) return;
  try {
    const nlohmann::json top = ReadJsonFile(file);
    if (!top.is_object() || !top.contains("uploads") || !top["uploads"].is_array())
      FailInvalid(file.string() +
                  ": expected {\"uploads\": [{\"tenant\", \"sha256\", \"bytes\", \"noted_unix_ms\"}, ...]}");
    // The file keeps Unix ms; retention's cutoff is on the file clock: each time is placed as far
    // before now on that clock as it is on the wall clock.
    const auto now = Time::clock::now();
    const std::int64_t now_unix_ms = NowUnixMs();
    decltype(tenants_) read;
    for (const auto& upload : top["uploads"]) {
      const auto entry = upload.is_object() ? upload : nlohmann::json::object();
      const auto text = [&](const char* key) { return entry.value(key, nlohmann::json()).is_string(); };
      const auto number = [&](const char* key) {
        return entry.value(key, nlohmann::json()).is_number_integer();
      };
      if (!text("tenant") || !text("sha256") || !number("bytes") || !number("noted_unix_ms"))
        FailInvalid(
            file.string() +
            ": an upload is not {\"tenant\", \"sha256\", \"bytes\", \"noted_unix_ms\"}: " + upload.dump());
      const auto noted_unix_ms = entry["noted_unix_ms"].get<std::int64_t>();
      read[entry["tenant"].get<std::string>()][entry["sha256"].get<std::string>()] = {
          entry["bytes"].get<std::int64_t>(),
          now - std::chrono::duration_cast<Time::duration>(
                    std::chrono::milliseconds(std::max<std::int64_t>(0, now_unix_ms - noted_unix_ms))),
          noted_unix_ms};
    }
    tenants_ = std::move(read);
  } catch (const Error& e) {
    spdlog::warn("{}; the uploads not yet submitted from before this start count again when resumed",
                 e.what());
  }
}

void UploadLedger::Save() const {
  if (file_.empty()) return;
  nlohmann::json uploads = nlohmann::json::array();
  for (const auto& [tenant, files] : tenants_) {
    for (const auto& [digest, entry] : files) {
      uploads.push_back({{"tenant", tenant},
                         {"sha256", digest},
                         {"bytes", entry.bytes},
                         {"noted_unix_ms", entry.noted_unix_ms}});
    }
  }
  try {
    WriteFile(file_, nlohmann::json{{"uploads", uploads}}.dump(1) + "\n", "uploads not yet submitted");
  } catch (const Error& e) {
    spdlog::error("{} (the uploads not yet submitted are kept in memory until the next change)", e.what());
  }
}

std::map<std::string, UploadLedger::Pending> UploadLedger::Tenants() const {
  std::map<std::string, Pending> tenants;
  for (const auto& [tenant, files] : tenants_) {
    auto& pending = tenants[tenant];
    for (const auto& [digest, entry] : files) {
      ++pending.files;
      pending.bytes += entry.bytes;
      pending.last_unix_ms = std::max(pending.last_unix_ms, entry.noted_unix_ms);
    }
  }
  return tenants;
}

std::vector<std::string> UploadLedger::Drop(const std::string& tenant) {
  std::vector<std::string> digests;
  const auto found = tenants_.find(tenant);
  if (found == tenants_.end()) return digests;
  for (const auto& [digest, entry] : found->second) digests.push_back(digest);
  tenants_.erase(found);
  Save();
  return digests;
}

bool UploadLedger::Holds(const std::string& sha256) const {
  return std::any_of(tenants_.begin(), tenants_.end(),
                     [&](const auto& tenant) { return tenant.second.count(sha256) > 0; });
}

}  // namespace endorecon::server
