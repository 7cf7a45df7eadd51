#include "server/tenant_quotas.h"

#include <fstream>
#include <nlohmann/json.hpp>

#include "common/error.h"
#include "server/principal.h"

namespace endorecon::server {

TenantQuotas::TenantQuotas(Quota defaults, const std::filesystem::path& file) : defaults_(defaults) {
  if (defaults.max_jobs < 0 || defaults.max_bytes < 0) FailInvalid("tenant quotas must not be negative");
  if (file.empty()) return;
  std::ifstream in(file);
  if (!in) Fail(ErrorCode::kNotFound, "--quotas " + file.string() + ": cannot be read");
  const auto json = nlohmann::json::parse(in, nullptr, false);
  if (json.is_discarded() || !json.is_object())
    FailInvalid("--quotas " + file.string() + ": expected a JSON object of tenants");
  for (const auto& [tenant, limits] : json.items()) {
    try {
      ValidateTenant(tenant);
    } catch (const Error& e) {
      FailInvalid("--quotas " + file.string() + ": " + e.what());
    }
    if (!limits.is_object()) FailInvalid("--quotas " + file.string() + ": '" + tenant + "' is not an object");
    Quota quota = defaults;
    for (const auto& [key, value] : limits.items()) {
      if (!value.is_number_integer() || value.get<std::int64_t>() < 0) {
        FailInvalid("--quotas " + file.string() + ": " + tenant + "." + key + " must be an integer >= 0");
      }
      if (key == "max_jobs") {
        quota.max_jobs = value.get<std::int64_t>();
      } else if (key == "max_bytes") {
        quota.max_bytes = value.get<std::int64_t>();
      } else {
        FailInvalid("--quotas " + file.string() + ": " + tenant + "." + key +
                    " is not max_jobs or max_bytes");
      }
    }
    tenants_[tenant] = quota;
  }
}

Quota TenantQuotas::For(const std::string& tenant) const {
  const auto found = tenants_.find(tenant);
  return found == tenants_.end() ? defaults_ : found->second;
}

}  // namespace endorecon::server
