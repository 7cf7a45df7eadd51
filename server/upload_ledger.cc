#include "server/upload_ledger.h"

#include <algorithm>
#include <set>

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

void UploadLedger::Add(const std::string& tenant, const v1::FileEntry& file, Time now) {
  if (file.sha256().empty()) return;  // a sizes-only listing brings nothing yet
  tenants_[tenant][file.sha256()] = {file.size(), now, NowUnixMs()};
}

void UploadLedger::Submitted(const std::string& tenant, const v1::Manifest& manifest) {
  const auto found = tenants_.find(tenant);
  if (found == tenants_.end()) return;
  for (const auto& file : manifest.files()) found->second.erase(file.sha256());
  if (found->second.empty()) tenants_.erase(found);
}

std::size_t UploadLedger::ForgetBefore(Time cutoff) {
  std::size_t forgotten = 0;
  for (auto tenant = tenants_.begin(); tenant != tenants_.end();) {
    auto& files = tenant->second;
    forgotten += std::erase_if(files, [cutoff](const auto& item) { return item.second.noted < cutoff; });
    tenant = files.empty() ? tenants_.erase(tenant) : std::next(tenant);
  }
  return forgotten;
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
  return digests;
}

bool UploadLedger::Holds(const std::string& sha256) const {
  return std::any_of(tenants_.begin(), tenants_.end(),
                     [&](const auto& tenant) { return tenant.second.count(sha256) > 0; });
}

}  // namespace endorecon::server
