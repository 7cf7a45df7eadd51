// endorecon-server token create|list|revoke --data-dir DIR: the token store of a data folder.
// Run it as the server's user, so the store's files stay readable by the server.
#include <fmt/format.h>
#include <fmt/ranges.h>
#include <pwd.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <iostream>
#include <iterator>
#include <map>
#include <memory>
#include <set>
#include <vector>

#include "common/error.h"
#include "common/private_folder.h"
#include "server/audit_log.h"
#include "server/commands.h"
#include "server/data_folder.h"
#include "server/job_coordinator.h"
#include "server/token_store.h"
#include "server/unix_time.h"

namespace endorecon::server {
namespace {

struct TokenFlags {
  std::string data_dir = "endorecon-data";
  std::string audit_log;
  std::string role;
  std::string tenant;
  bool tenant_given = false;  // --tenant given, perhaps empty
  std::string name;
  double expires_in_s = 0;
  CLI::Option* expires_in = nullptr;  // not given: the token never expires
};

std::string LocalUser() {
  const passwd* user = getpwuid(geteuid());
  return "local:" + std::string(user ? user->pw_name : std::to_string(geteuid()));
}

// The store, created (in the data folder, which must exist) only for `create`: reading or revoking
// never makes one, since a running server requires tokens once its store holds one.
std::unique_ptr<TokenStore> OpenStore(const TokenFlags& flags, bool create) {
  // A misspelt --data-dir said "no token store" (as if tokens were off), and `create` made a folder
  // of its own that no server reads: the folder must exist, for every subcommand.
  std::error_code error;
  if (!std::filesystem::is_directory(flags.data_dir, error)) {
    Fail(ErrorCode::kNotFound,
         "--data-dir " + flags.data_dir +
             (std::filesystem::exists(flags.data_dir, error) ? ": not a folder" : ": no such folder") +
             ": name the server's data folder (a new deployment's is created first: install -d -m 700 DIR)");
  }
  RefuseAStoreBesideIt(flags.data_dir);  // a second token store, which a move of the data overwrote
  RefuseRootInAnotherUsersFolder(flags.data_dir, "endorecon-server token");
  const auto path = TokenStore::PathIn(flags.data_dir);
  if (!create && !std::filesystem::exists(path)) return nullptr;
  if (create && MakePrivateFolder(flags.data_dir)) {
    spdlog::warn("{} is open to its group or others: make it its owner's alone (chmod 700)", flags.data_dir);
  }
  return std::make_unique<TokenStore>(path);
}

void Audit(const TokenFlags& flags, const std::string& method, const TokenRecord& record) {
  AuditLog log(flags.audit_log.empty() ? std::filesystem::path(flags.data_dir) / "audit.jsonl"
                                       : std::filesystem::path(flags.audit_log));
  log.Write({LocalUser(), "-", record.tenant, method, "", "OK", "", "", record.name});
}

// A worker token's tenant is a name typed by hand, and the server keeps no list of tenants: a
// misspelt one ("radiolgy") made workers that leased nothing, and nothing said why (found
// 2026-12-06). Tenants are made by client tokens, so one that no active client token names is
// warned of (the token is still made: its client tokens may come next).
void WarnOfAnUnknownTenant(TokenStore& store, const std::string& tenant, std::int64_t now) {
  std::set<std::string> tenants;
  std::vector<std::string> lapsed;  // the tenant's client tokens no longer active, "'c-1' was revoked"
  for (const auto& record : store.List()) {
    if (record.role != Role::kClient) continue;
    const auto state = record.StateAt(now);
    if (state == "active") {
      tenants.insert(record.tenant);
    } else if (record.tenant == tenant) {
      lapsed.push_back(fmt::format("'{}' {}", record.name, state == "revoked" ? "was revoked" : "expired"));
    }
  }
  if (tenants.count(tenant)) return;
  tenants.erase("");
  // Named up to ten: a hospital with many tenants got one long line.
  constexpr std::size_t kNamed = 10;
  std::vector<std::string> named(tenants.begin(),
                                 std::next(tenants.begin(), std::min(tenants.size(), kNamed)));
  const std::string more =
      tenants.size() > kNamed ? fmt::format(" and {} more", tenants.size() - kNamed) : "";
  std::cerr << fmt::format(
      "warning: no active client token is for tenant '{}' ({}{}): this worker token's workers run that "
      "tenant's jobs only, so check the name\n",
      tenant, lapsed.empty() ? "" : fmt::format("its client token(s): {}; ", fmt::join(lapsed, ", ")),
      tenants.empty() ? "no active client token has a tenant"
                      : fmt::format("active client tokens are for {}{}", fmt::join(named, ", "), more));
}

int Create(const TokenFlags& flags) {
  const auto role = ParseRole(flags.role);
  if (!role) FailInvalid("--role " + flags.role + ": expected client, worker or admin");
  // `--tenant "$TENANT"` with the variable unset made a worker token that serves every tenant.
  if (flags.tenant_given && flags.tenant.empty())
    FailInvalid(
        "--tenant is empty: name the tenant, or leave --tenant out (a worker token then serves every "
        "tenant)");
  if (*role == Role::kAdmin && !flags.tenant.empty()) {
    FailInvalid(
        "--tenant applies to client tokens (whose jobs are that tenant's) and worker tokens (which then run "
        "that tenant's jobs only): an admin token sees every tenant");
  }
  const bool expires_given = flags.expires_in != nullptr && flags.expires_in->count() > 0;
  if (expires_given && (flags.expires_in_s <= 0 || !(flags.expires_in_s <= 100.0 * 366 * 86400)))
    FailInvalid("--expires-in must be positive and at most 100 years, as 90d, 12h or 30m");
  const std::int64_t now = NowUnixMs();
  const std::int64_t expires = expires_given ? now + static_cast<std::int64_t>(flags.expires_in_s * 1000) : 0;
  ValidateTokenRequest(flags.name, *role, flags.tenant, expires, now);  // before a store is made
  const auto store = OpenStore(flags, true);
  const auto token = store->Create(flags.name, *role, flags.tenant, expires);
  Audit(flags, "TokenCreate", {flags.name, *role, flags.tenant, 0, 0, expires});
  if (*role == Role::kWorker && !flags.tenant.empty()) WarnOfAnUnknownTenant(*store, flags.tenant, now);
  // The token alone on stdout, so that T=$(... token create ...) takes it; what it is, on stderr (the
  // two lines were both on stdout, and $(...) took both; found 2026-12-07).
  std::cerr << fmt::format(
      "created {} token '{}'{}{}; it is shown only now, keep it in a file only its user can "
      "read (chmod 600):\n",
      RoleName(*role), flags.name, flags.tenant.empty() ? "" : fmt::format(" for tenant '{}'", flags.tenant),
      expires ? fmt::format(" valid until {} UTC", UtcTime(expires)) : "");
  std::cout << token << "\n";
  return 0;
}

int List(const TokenFlags& flags) {
  const auto store = OpenStore(flags, false);
  if (!store) {
    std::cout << "no token store in " << flags.data_dir
              << ": no token was created, and a server on this folder requires none\n";
    return 0;
  }
  const auto records = store->List();
  const std::int64_t now = NowUnixMs();
  std::cout << fmt::format("{:<24} {:<7} {:<16} {:<20} {:<20} {}\n", "NAME", "ROLE", "TENANT",
                           "CREATED (UTC)", "EXPIRES (UTC)", "STATE");
  for (const auto& record : records) {
    const auto state = record.StateAt(now);
    std::cout << fmt::format("{:<24} {:<7} {:<16} {:<20} {:<20} {}{}\n", record.name, RoleName(record.role),
                             record.tenant.empty() ? "-" : record.tenant, UtcTime(record.created_unix_ms),
                             record.expires_unix_ms ? UtcTime(record.expires_unix_ms) : "never", state,
                             state == "revoked" ? " " + UtcTime(record.revoked_unix_ms) : "");
  }
  return 0;
}

int Revoke(const TokenFlags& flags) {
  const auto store = OpenStore(flags, false);
  if (!store)
    Fail(ErrorCode::kNotFound,
         "no token store in " + flags.data_dir + ": no token named '" + flags.name + "'");
  const auto record = store->Revoke(flags.name);
  Audit(flags, "TokenRevoke", record);
  if (record.expires_unix_ms != 0 && record.revoked_unix_ms == record.expires_unix_ms) {
    std::cout << "token '" << record.name << "' had expired at " << UtcTime(record.expires_unix_ms)
              << " UTC already; set aside (its expiry no longer reported, its name free)\n";
  } else {
    std::cout << "revoked token '" << record.name << "'; calls with it are refused from now on\n";
  }
  return 0;
}

void AddCommonFlags(CLI::App& command, TokenFlags& flags) {
  command.add_option("--data-dir", flags.data_dir, "the server's data folder")->capture_default_str();
  command.add_option("--audit-log", flags.audit_log, "audit log (default: DATA_DIR/audit.jsonl)");
}

}  // namespace

Command AddTokenCommand(CLI::App& app) {
  auto flags = std::make_shared<TokenFlags>();
  auto* token =
      app.add_subcommand("token", "create, list or revoke bearer tokens (works while the server runs)");
  token->require_subcommand(1);
  auto* create = token->add_subcommand("create", "create a token and print it once (its last word)");
  AddCommonFlags(*create, *flags);
  create->add_option("--role", flags->role, "client (its tenant's jobs), worker (the worker API) or admin")
      ->required();
  create
      ->add_option("--tenant", flags->tenant,
                   "the tenant whose jobs a client token works on, or the one tenant whose jobs a worker "
                   "token runs (without it: every tenant's)")
      ->each([flags](const std::string&) { flags->tenant_given = true; });
  create->add_option("--name", flags->name, "a label for the token (audit log, list, revoke)")->required();
  flags->expires_in =
      create
          ->add_option(
              "--expires-in", flags->expires_in_s,
              "refuse the token after this long: a number with a unit (s, m, h, d or w), as 90d, 1.5h or 30m (default: never)")
          ->transform(CLI::AsNumberWithUnit(
              std::map<std::string, double>{{"s", 1}, {"m", 60}, {"h", 3600}, {"d", 86400}, {"w", 604800}},
              CLI::AsNumberWithUnit::UNIT_REQUIRED, "DURATION"));
  auto* list = token->add_subcommand(
      "list", "list tokens: name, role, tenant, created, expiry, and whether active, revoked or expired");
  AddCommonFlags(*list, *flags);
  auto* revoke = token->add_subcommand("revoke", "revoke the active token with this label");
  AddCommonFlags(*revoke, *flags);
  revoke->add_option("NAME", flags->name, "the token's label")->required();
  return [flags, create, list] {
    if (create->parsed()) return Create(*flags);
    if (list->parsed()) return List(*flags);
    return Revoke(*flags);
  };
}

}  // namespace endorecon::server
