#include "server/unix_time.h"

#include <fmt/chrono.h>

#include <chrono>
#include <ctime>

namespace endorecon::server {

std::int64_t NowUnixMs() {
  return std::chrono::duration_cast<std::chrono::milliseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

std::string UtcTime(std::int64_t unix_ms) {
  return fmt::format("{:%Y-%m-%d %H:%M:%S}", fmt::gmtime(static_cast<std::time_t>(unix_ms / 1000)));
}

std::string UtcText(std::int64_t unix_ms) { return UtcTime(unix_ms) + " UTC"; }

}  // namespace endorecon::server
