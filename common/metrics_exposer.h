// The /metrics endpoint of the server and of a worker (prometheus-cpp's Exposer, on CivetServer).
// Header-only: its users link prometheus-cpp::pull themselves; endorecon_common does not.
#pragma once

#include <prometheus/exposer.h>

#include <memory>
#include <string>

#include "common/error.h"

namespace endorecon {

// Serves /metrics on `bind_address` (HOST:PORT). Throws Error(kUnavailable) naming the address and
// the flags when it cannot, as a taken --listen port is: CivetServer's own words ("null context when
// constructing CivetServer") name neither the port nor the flag, and are left out.
inline std::unique_ptr<prometheus::Exposer> OpenMetricsExposer(const std::string& bind_address) {
  try {
    return std::make_unique<prometheus::Exposer>(bind_address);
  } catch (const std::exception&) {
    Fail(ErrorCode::kUnavailable,
         "cannot serve metrics on " + bind_address +
             " (--metrics-host, --metrics-port): the port is taken or the address is "
             "not this machine's");
  }
}

}  // namespace endorecon
