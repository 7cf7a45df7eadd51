// The /metrics endpoint of the server and of a worker (prometheus-cpp's Exposer, on CivetServer).
// Header-only: its users link prometheus-cpp::pull themselves; endorecon_common does not.
#pragma once

#include <prometheus/exposer.h>

#include <memory>
#include <string>

#include "common/error.h"

namespace endorecon {

// HOST:PORT of --metrics-host and --metrics-port, an IPv6 host in brackets ("[::]:9465"): "::" made
// ":::9465", which nothing could serve (found 2026-12-07).
inline std::string MetricsAddress(const std::string& host, int port) {
  const bool v6 = host.find(':') != std::string::npos && host.front() != '[';
  return (v6 ? "[" + host + "]" : host) + ":" + std::to_string(port);
}

// Serves /metrics on `bind_address` (HOST:PORT). Throws Error(kInvalidArgument) for an IPv6 address,
// which this build cannot serve, else Error(kUnavailable) naming the address and
// the flags when it cannot, as a taken --listen port is: CivetServer's own words ("null context when
// constructing CivetServer") name neither the port nor the flag, and are left out.
inline std::unique_ptr<prometheus::Exposer> OpenMetricsExposer(const std::string& bind_address) {
  try {
    return std::make_unique<prometheus::Exposer>(bind_address);
  } catch (const std::exception&) {
    // Debian's civetweb is built without IPv6: "[::]:9465" cannot be served whatever the machine has.
    const bool v6 = !bind_address.empty() && bind_address.front() == '[';
    Fail(v6 ? ErrorCode::kInvalidArgument : ErrorCode::kUnavailable,
         "cannot serve metrics on " + bind_address + " (--metrics-host, --metrics-port): " +
             (v6 ? "this build's HTTP server (civetweb) serves IPv4 only: give an IPv4 address, or 0.0.0.0 "
                   "for every interface"
                 : "the port is taken or the address is not this machine's"));
  }
}

}  // namespace endorecon
