#include "server/principal.h"

#include "common/error.h"
#include "common/job_bounds.h"

namespace endorecon::server {

const char* RoleName(Role role) {
  switch (role) {
    case Role::kClient:
      return "client";
    case Role::kWorker:
      return "worker";
    case Role::kAdmin:
      return "admin";
  }
  return "unknown";
}

void ValidateTenant(const std::string& tenant) {
  if (tenant.empty() || tenant.size() > 63 ||
      tenant.find_first_not_of("abcdefghijklmnopqrstuvwxyz0123456789._-") != std::string::npos ||
      tenant.find_first_of("._-") == 0) {
    FailInvalid("tenant '" + PrintableText(tenant, 64) +
                "': expected 1-63 characters of a-z, 0-9, '.', '_', '-', starting with a letter or digit");
  }
}

std::optional<Role> ParseRole(std::string_view name) {
  if (name == "client") return Role::kClient;
  if (name == "worker") return Role::kWorker;
  if (name == "admin") return Role::kAdmin;
  return std::nullopt;
}

}  // namespace endorecon::server
