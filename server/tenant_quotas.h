// Per-tenant limits: how many jobs a tenant may have QUEUED or RUNNING at once, and how many bytes
// its jobs may keep stored (clips, results, checkpoints; JobStore's StoredBytes). Defaults apply
// to every tenant (--tenant-max-jobs, --tenant-max-bytes); a JSON file (--quotas FILE) sets them
// per tenant:
//
//   {"radiology": {"max_jobs": 20, "max_bytes": 500000000000}, "research": {"max_jobs": 2}}
//
// A key left out takes the default; 0 means no limit.
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <string>

namespace endorecon::server {

struct Quota {
  std::int64_t max_jobs = 0;   // 0: no limit
  std::int64_t max_bytes = 0;  // 0: no limit
};

class TenantQuotas {
 public:
  TenantQuotas() = default;
  // Throws Error(kInvalidArgument) naming the file and the key for a malformed file, an unknown key
  // or a negative value; kNotFound when the file cannot be read. An empty `file`: defaults only.
  TenantQuotas(Quota defaults, const std::filesystem::path& file);

  Quota For(const std::string& tenant) const;

 private:
  Quota defaults_;
  std::map<std::string, Quota> tenants_;
};

}  // namespace endorecon::server
