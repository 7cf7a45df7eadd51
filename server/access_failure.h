// A file or folder of the server's own (its stores, blobs, audit log) that this user could not open
// or use. Permissions (a restored copy another user owns, a read-only mount) are the operator's to
// fix: FAILED_PRECONDITION, saying to chown; anything else may pass: UNAVAILABLE. They were
// UNAVAILABLE, which a supervisor restarts for ever, or worse taken for damage (found 2026-12-07).
#pragma once

#include <string>

namespace endorecon::server {

// Throws Error: "WHAT: <the system's reason>", with the chown hint for a permission `error` (errno).
[[noreturn]] void FailAccess(const std::string& what, int error);

}  // namespace endorecon::server
