#include "server/idle_trim.h"

#include <malloc.h>

namespace endorecon::server {

void IdleTrim::Received(std::int64_t bytes) {
  if (bytes <= 0) return;
  last_received_ns_.store(
      std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now().time_since_epoch()).count(),
      std::memory_order_relaxed);
}

bool IdleTrim::Tick(Clock::time_point now) {
  const std::int64_t last = last_received_ns_.load(std::memory_order_relaxed);
  if (last == 0) return false;
  const auto since = now.time_since_epoch() - std::chrono::nanoseconds(last);
  if (since < quiet_) return false;
  // Bytes that arrive between the load and here only mean the next burst's trim waits for it.
  std::int64_t expected = last;
  if (!last_received_ns_.compare_exchange_strong(expected, 0, std::memory_order_relaxed)) return false;
  malloc_trim(0);
  return true;
}

}  // namespace endorecon::server
