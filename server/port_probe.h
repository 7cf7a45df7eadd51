// Whether a listening address is free, asked before the server opens its data folder: a taken port
// was reported only after the job store had been opened and its running jobs requeued.
#pragma once

#include <string>

namespace endorecon::server {

// Binds a socket to `listen` ("host:port", "[v6]:port") and lets it go. Throws Error(kUnavailable)
// naming the address when the port is taken (EADDRINUSE; gRPC's own bind stays the last word, as the
// port may be taken in between). Port 0, "unix:" addresses and names that do not resolve are left to
// gRPC.
void CheckPortFree(const std::string& listen);

}  // namespace endorecon::server
