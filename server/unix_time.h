// The wall clock as the job store keeps times: milliseconds since the Unix epoch.
#pragma once

#include <cstdint>

namespace endorecon::server {

std::int64_t NowUnixMs();

}  // namespace endorecon::server
