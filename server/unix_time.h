// The wall clock as the job store keeps times: milliseconds since the Unix epoch.
#pragma once

#include <cstdint>
#include <string>

namespace endorecon::server {

std::int64_t NowUnixMs();
// "2026-12-05 09:18:17": a time in UTC, as messages and `token list` show times.
std::string UtcTime(std::int64_t unix_ms);
// The same, ending " UTC", for messages.
std::string UtcText(std::int64_t unix_ms);

}  // namespace endorecon::server
