// endorecon uploads [--drop] [--tenant T]: the uploads not yet submitted (an upload interrupted, or one
// whose submit never came) count against the tenant's byte quota until submitted, or until the
// server's --orphan-hours after the last of them. This lists them, and --drop gives them up: they
// stop counting and the server deletes their files (those no job or other upload holds). A client
// sees its own tenant's; an admin every tenant's, and drops a tenant's named with --tenant.
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <iostream>

#include "client/commands.h"
#include "client/exit_codes.h"
#include "client/job_format.h"
#include "common/grpc_status.h"
#include "common/transport_security.h"

namespace endorecon::client {
namespace {

// Tenant "" is that of admins, and the one tenant of a server without tokens; --tenant names it '-'.
std::string Whose(const std::string& tenant) {
  return tenant.empty() ? "no tenant ('-')" : "tenant '" + tenant + "'";
}

std::string Described(const v1::TenantUploads& uploads) {
  // The bytes count whole against the quota; an interrupted upload holds less on the disk.
  const std::string arrived = uploads.arrived_bytes() < uploads.bytes()
                                  ? " (" + HumanBytes(uploads.arrived_bytes()) + " of it arrived)"
                                  : "";
  // The server keeps one file a content: a clip of 7,501 files with identical masks listed "6653
  // file(s)" and read as files lost (found 2026-12-06).
  return fmt::format("{} distinct file(s), {}{}, the last upload begun {}", uploads.files(),
                     HumanBytes(uploads.bytes()), arrived, HumanTime(uploads.last_unix_ms()));
}

}  // namespace

Command AddUploadsCommand(CLI::App& app) {
  auto request = std::make_shared<v1::UploadsRequest>();
  auto* sub =
      app.add_subcommand("uploads",
                         "list the uploads waiting to be submitted (an interrupted one, say), which count "
                         "against the tenant's byte quota; --drop gives them up");
  sub->add_flag(
      "--drop", [request](std::int64_t) { request->set_drop(true); },
      "give them up: they stop counting, and the server deletes their files that no job or other tenant's "
      "upload holds");
  sub->add_option("--tenant", *request->mutable_tenant(),
                  "an admin's: the tenant to list or drop ('-' for that of admins; without it an admin lists "
                  "every tenant's); a client acts on its own tenant's");
  return [request](const Globals& globals) {
    v1::UploadsResponse response;
    auto context = CallContext(globals.timeout());
    ThrowIfFailed(globals.Connect()->Uploads(context.get(), *request, &response),
                  request->drop() ? "uploads --drop" : "uploads");
    if (globals.json) {
      std::cout << ToJson(response) << std::endl;
      return kExitOk;
    }
    const std::string whose = request->tenant().empty() ? "" : " of tenant '" + request->tenant() + "'";
    if (request->drop()) {
      if (response.tenants_size() == 0) {
        std::cout << "no uploads" << whose << " waiting to be submitted: nothing dropped" << std::endl;
        return kExitOk;
      }
      const auto& dropped = response.tenants(0);
      std::cout << "dropped the uploads waiting to be submitted (" << Whose(dropped.tenant())
                << "): " << Described(dropped);
      // The server tells an admin what it deleted; a client, nothing that would say which of its files
      // another tenant holds.
      if (response.has_deleted_files()) {
        std::cout << "; deleted " << response.deleted_files() << " file(s), "
                  << HumanBytes(response.deleted_bytes())
                  << ", from the server (a file a job or another upload holds is kept)";
      } else {
        std::cout << "; they no longer count against the byte quota";
      }
      std::cout << std::endl;
      return kExitOk;
    }
    if (response.tenants_size() == 0) {
      std::cout << "no uploads" << whose << " waiting to be submitted" << std::endl;
      return kExitOk;
    }
    std::cout
        << "uploads waiting to be submitted (they count against the tenant's byte quota until submitted, "
           "or dropped with `endorecon uploads --drop`):"
        << std::endl;
    for (const auto& uploads : response.tenants()) {
      std::cout << "  " << Whose(uploads.tenant()) << ": " << Described(uploads) << std::endl;
    }
    return kExitOk;
  };
}

}  // namespace endorecon::client
