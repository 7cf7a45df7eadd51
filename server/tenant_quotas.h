// Per-tenant limits: how many jobs a tenant may have QUEUED or RUNNING at once, and how many bytes
// its jobs may keep stored (clips, results, checkpoints; JobStore's StoredBytes). Defaults apply
// to every tenant (--tenant-max-jobs, --tenant-max-bytes); a JSON file (--quotas FILE) sets them
// per tenant:
//
//   {"radiology": {"max_jobs": 20, "max_bytes": 500000000000}, "research": {"max_jobs": 2}}
//
// A key left out takes the default; 0 means no limit. The file is read again when it changes (its
// time or size: Refresh, at each check), so an admin raises a tenant's quota without a restart; a
// changed file that does not read is logged and the quotas read before stay in force.
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

  // Reads the file again when its time or size changed since it was last read; returns whether the
  // quotas in force changed. A file that no longer reads is logged (once a change) and left aside.
  bool Refresh();

  Quota For(const std::string& tenant) const;

  // The quotas in force, for the log: "defaults max_jobs 20, max_bytes 0 (no limit); from FILE:
  // radiology max_jobs 3, max_bytes 600000".
  std::string Describe() const;

 private:
  using Tenants = std::map<std::string, Quota>;
  static Tenants Read(Quota defaults, const std::filesystem::path& file);

  Quota defaults_;
  Tenants tenants_;
  std::filesystem::path file_;
  std::filesystem::file_time_type modified_{};  // the file's, when last read (or tried)
  std::uintmax_t size_ = 0;
};

}  // namespace endorecon::server
