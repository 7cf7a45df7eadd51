#include "server/unix_time.h"

#include <chrono>

namespace endorecon::server {

std::int64_t NowUnixMs() {
  return std::chrono::duration_cast<std::chrono::milliseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

}  // namespace endorecon::server
