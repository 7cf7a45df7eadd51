// Who is calling: the token's label, its role and its tenant. On a server without a token store
// every caller is the anonymous principal, which may do everything (loopback use, the demo).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace endorecon::server {

enum class Role {
  kClient,  // the job API for its own tenant's jobs
  kWorker,  // the worker API only
  kAdmin,   // the job API for every tenant, the worker list, cancelling anything
};

const char* RoleName(Role role);
// "client", "worker" or "admin"; nullopt otherwise.
std::optional<Role> ParseRole(std::string_view name);

struct Principal {
  std::string name;  // the token's label; "anonymous" without a token store
  Role role = Role::kAdmin;
  std::string tenant;  // "" for anonymous callers and for tokens without a tenant
  bool anonymous = true;
  std::int64_t token_expires_unix_ms = 0;  // when the caller's token expires; 0: never (or no token)

  // True when the caller's view of jobs is not limited to one tenant.
  bool SeesAllTenants() const { return anonymous || role == Role::kAdmin; }
};

// Throws Error(kInvalidArgument) unless `tenant` is 1-63 characters of a-z, 0-9, '.', '_', '-'
// starting with a letter or digit (it appears in paths, logs and metrics). The message shows the
// name as printable text, cut short.
void ValidateTenant(const std::string& tenant);

inline Principal AnonymousPrincipal() { return Principal{"anonymous", Role::kAdmin, "", true}; }
// The server acting on its own behalf (PACS retrievals and sends, which follow the jobs of every
// tenant); named "server" as in the audit log's entries for such actions.
inline Principal ServerPrincipal() { return Principal{"server", Role::kAdmin, "", false}; }

}  // namespace endorecon::server
