#include "server/idle_trim.h"

#include <malloc.h>

namespace endorecon::server {

void IdleTrim::Received(std::int64_t bytes) {
  if (bytes <= 0) return;
  last_received_.store(Clock::now().time_since_epoch().count(), std::memory_order_relaxed);
}

bool IdleTrim::Tick(Clock::time_point now) {
  const Clock::rep last = last_received_.load(std::memory_order_relaxed);
  if (last == 0 || now.time_since_epoch() - Clock::duration(last) < quiet_) return false;
  // Bytes that arrive between the load and here only mean the next burst's trim waits for it.
  Clock::rep expected = last;
  if (!last_received_.compare_exchange_strong(expected, 0, std::memory_order_relaxed)) return false;
  malloc_trim(0);
  return true;
}

}  // namespace endorecon::server
