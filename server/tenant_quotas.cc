#include "server/tenant_quotas.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <nlohmann/json.hpp>

#include "common/error.h"
#include "common/json_file.h"
#include "server/principal.h"

namespace endorecon::server {

namespace {

std::string Limits(const Quota& quota) {
  const auto limit = [](std::int64_t value) {
    return std::to_string(value) + (value == 0 ? " (no limit)" : "");
  };
  return "max_jobs " + limit(quota.max_jobs) + ", max_bytes " + limit(quota.max_bytes);
}

}  // namespace

TenantQuotas::TenantQuotas(Quota defaults, const std::filesystem::path& file)
    : defaults_(defaults), file_(file) {
  if (defaults.max_jobs < 0 || defaults.max_bytes < 0) FailInvalid("tenant quotas must not be negative");
  if (file.empty()) return;
  std::error_code error;
  modified_ = std::filesystem::last_write_time(file, error);
  size_ = std::filesystem::file_size(file, error);
  tenants_ = Read(defaults, file);
}

bool TenantQuotas::Refresh() {
  if (file_.empty()) return false;
  std::error_code error;
  const auto modified = std::filesystem::last_write_time(file_, error);
  const auto size = error ? 0 : std::filesystem::file_size(file_, error);
  if (!error && modified == modified_ && size == size_) return false;
  if (error && modified_ == std::filesystem::file_time_type{}) return false;  // gone, and said so already
  modified_ = error ? std::filesystem::file_time_type{} : modified;
  size_ = size;
  try {
    if (error) Fail(ErrorCode::kNotFound, "--quotas " + file_.string() + ": " + error.message());
    Tenants read = Read(defaults_, file_);
    const bool changed =
        read.size() != tenants_.size() ||
        !std::equal(read.begin(), read.end(), tenants_.begin(), [](const auto& a, const auto& b) {
          return a.first == b.first && a.second.max_jobs == b.second.max_jobs &&
                 a.second.max_bytes == b.second.max_bytes;
        });
    tenants_ = std::move(read);
    spdlog::info("quotas read again, the file having changed: {}", Describe());
    return changed;
  } catch (const Error& e) {
    spdlog::error("{}; the quotas read before stay in force: {}", e.what(), Describe());
    return false;
  }
}

std::string TenantQuotas::Describe() const {
  std::string text = "defaults " + Limits(defaults_);
  if (file_.empty()) return text;
  text += "; from " + file_.string() + ":";
  if (tenants_.empty()) return text + " no tenant";
  bool first = true;
  for (const auto& [tenant, quota] : tenants_) {
    text += (first ? " " : "; ") + tenant + " " + Limits(quota);
    first = false;
  }
  return text;
}

TenantQuotas::Tenants TenantQuotas::Read(Quota defaults, const std::filesystem::path& file) {
  Tenants tenants;
  std::error_code missing;
  if (!std::filesystem::exists(file, missing))
    Fail(ErrorCode::kNotFound, "--quotas " + file.string() + ": no such file");
  nlohmann::json json;
  try {
    json = ReadJsonFile(file);  // a FIFO refused, a syntax error placed (line, column)
  } catch (const Error& e) {
    FailInvalid("--quotas " + std::string(e.what()));
  }
  if (!json.is_object()) FailInvalid("--quotas " + file.string() + ": expected a JSON object of tenants");
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
    tenants[tenant] = quota;
  }
  return tenants;
}

Quota TenantQuotas::For(const std::string& tenant) const {
  const auto found = tenants_.find(tenant);
  return found == tenants_.end() ? defaults_ : found->second;
}

}  // namespace endorecon::server
