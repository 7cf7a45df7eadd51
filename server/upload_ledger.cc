#include "server/upload_ledger.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <nlohmann/json.hpp>
#include <set>
#include <utility>

#include "common/error.h"
#include "common/file_write.h"
#include "common/job_bounds.h"
#include "common/json_file.h"
#include "common/manifest.h"
#include "server/principal.h"
#include "server/unix_time.h"

namespace endorecon::server {
namespace {

// Whether `entry` is one upload of the file: a tenant's name ("" for the admins'), a SHA-256 in hex,
// its bytes and when it was noted.
bool IsUpload(const nlohmann::json& entry) {
  if (!entry.is_object()) return false;
  const auto field = [&](const char* key) { return entry.value(key, nlohmann::json()); };
  const auto tenant = field("tenant"), sha256 = field("sha256"), bytes = field("bytes"),
             noted = field("noted_unix_ms");
  if (!tenant.is_string() || !sha256.is_string() || !bytes.is_number_integer() || !noted.is_number_integer())
    return false;
  if (!IsSha256Hex(sha256.get<std::string>())) return false;
  if (bytes.get<std::int64_t>() < 0 || noted.get<std::int64_t>() <= 0) return false;
  if (const auto name = tenant.get<std::string>(); !name.empty()) {
    try {
      ValidateTenant(name);
    } catch (const Error&) {
      return false;
    }
  }
  return true;
}

}  // namespace

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
  return found == tenants_.end() ? 0 : Summary(found->second).last_unix_ms;
}

bool UploadLedger::Add(const std::string& tenant, const v1::FileEntry& file, Time now) {
  if (file.sha256().empty()) return false;  // a sizes-only listing brings nothing yet
  auto& entry = tenants_[tenant][file.sha256()];
  entry = {file.size(), now, NowUnixMs(), entry.proven};
  return true;
}

void UploadLedger::NoteProven(const std::string& tenant, const std::string& sha256) {
  const auto found = tenants_.find(tenant);
  if (found == tenants_.end()) return;
  const auto entry = found->second.find(sha256);
  if (entry == found->second.end() || entry->second.proven) return;
  entry->second.proven = true;
  unsaved_ = true;
  if (std::chrono::steady_clock::now() - saved_at_ >= kProvenSaveInterval) Save();
}

void UploadLedger::Flush() {
  if (unsaved_) Save();
}

std::size_t UploadLedger::Noters(const std::string& sha256) const {
  return static_cast<std::size_t>(std::count_if(
      tenants_.begin(), tenants_.end(), [&](const auto& tenant) { return tenant.second.count(sha256) > 0; }));
}

void UploadLedger::SettleLegacy(const std::function<bool(const std::string&, const std::string&)>& proven) {
  bool settled = false;
  for (auto& [tenant, files] : tenants_) {
    for (auto& [digest, entry] : files) {
      if (!std::exchange(entry.legacy, false)) continue;
      entry.proven = proven(tenant, digest);
      settled = true;
    }
  }
  if (settled) Save();
}

std::vector<std::pair<std::string, std::string>> UploadLedger::Proven() const {
  std::vector<std::pair<std::string, std::string>> proven;
  for (const auto& [tenant, files] : tenants_) {
    for (const auto& [digest, entry] : files) {
      if (entry.proven) proven.emplace_back(tenant, digest);
    }
  }
  return proven;
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
    std::size_t left_out = 0;
    std::string first_left_out;
    for (const auto& upload : top["uploads"]) {
      // An entry that is no upload (edited by hand, or from a newer version) is left out and said.
      if (!IsUpload(upload)) {
        if (left_out++ == 0) first_left_out = PrintableText(upload.dump(), 200);
        continue;
      }
      const auto noted_unix_ms = upload["noted_unix_ms"].get<std::int64_t>();
      read[upload["tenant"].get<std::string>()][upload["sha256"].get<std::string>()] = {
          upload["bytes"].get<std::int64_t>(),
          now - std::chrono::duration_cast<Time::duration>(
                    std::chrono::milliseconds(std::max<std::int64_t>(0, now_unix_ms - noted_unix_ms))),
          noted_unix_ms, upload.value("proven", nlohmann::json(false)) == true, !upload.contains("proven")};
    }
    tenants_ = std::move(read);
    if (left_out > 0) {
      spdlog::warn(
          "{}: left out {} entr{} that are no upload ({}, expected {{\"tenant\", \"sha256\" (64 hex "
          "digits), \"bytes\" (>= 0), \"noted_unix_ms\" (> 0)}}){}",
          file.string(), left_out, left_out == 1 ? "y" : "ies", first_left_out,
          left_out > 1 ? ", the first shown" : "");
    }
    std::int64_t files = 0, bytes = 0;
    for (const auto& [tenant, pending] : Tenants()) {
      files += pending.files;
      bytes += pending.bytes;
    }
    if (files > 0) {
      spdlog::info("uploads waiting to be submitted, from {}: {} file(s), {} bytes, of {} tenant(s)",
                   file.string(), files, bytes, tenants_.size());
    }
  } catch (const Error& e) {
    spdlog::warn(
        "{}; the uploads waiting to be submitted from before this start are not counted or listed until "
        "resumed, and their partial files are deleted --orphan-hours after their last write",
        e.what());
  }
}

void UploadLedger::Save() {
  unsaved_ = false;
  saved_at_ = std::chrono::steady_clock::now();
  if (file_.empty()) return;
  nlohmann::json uploads = nlohmann::json::array();
  for (const auto& [tenant, files] : tenants_) {
    for (const auto& [digest, entry] : files) {
      uploads.push_back({{"tenant", tenant},
                         {"sha256", digest},
                         {"bytes", entry.bytes},
                         {"noted_unix_ms", entry.noted_unix_ms},
                         {"proven", entry.proven}});
    }
  }
  try {
    WriteFile(file_, nlohmann::json{{"uploads", uploads}}.dump(1) + "\n", "uploads not yet submitted");
  } catch (const Error& e) {
    spdlog::error("{} (the uploads not yet submitted are kept in memory until the next change)", e.what());
  }
}

UploadLedger::Pending UploadLedger::Summary(const std::map<std::string, Entry>& files) {
  Pending pending;
  for (const auto& [digest, entry] : files) {
    ++pending.files;
    pending.bytes += entry.bytes;
    pending.last_unix_ms = std::max(pending.last_unix_ms, entry.noted_unix_ms);
  }
  return pending;
}

std::map<std::string, UploadLedger::Pending> UploadLedger::Tenants() const {
  std::map<std::string, Pending> tenants;
  for (const auto& [tenant, files] : tenants_) tenants[tenant] = Summary(files);
  return tenants;
}

std::vector<std::pair<std::string, std::int64_t>> UploadLedger::Files(const std::string& tenant) const {
  std::vector<std::pair<std::string, std::int64_t>> files;
  if (const auto found = tenants_.find(tenant); found != tenants_.end()) {
    for (const auto& [digest, entry] : found->second) files.emplace_back(digest, entry.bytes);
  }
  return files;
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

bool UploadLedger::Holds(const std::string& sha256, Time since) const {
  return std::any_of(tenants_.begin(), tenants_.end(), [&](const auto& tenant) {
    const auto entry = tenant.second.find(sha256);
    return entry != tenant.second.end() && entry->second.noted >= since;
  });
}

}  // namespace endorecon::server
