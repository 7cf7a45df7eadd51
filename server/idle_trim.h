// Gives the memory a burst of uploads used back to the system once the burst is over. gRPC holds
// each stream's chunks (4 MiB messages, in the call's thread arena) while they arrive; glibc keeps
// what those arenas freed, so a server that took 1 GiB from 100 clients at once stayed hundreds of
// MB larger afterwards (bench/service_load). malloc_trim walks every arena, so it runs only when
// bytes arrived since the last trim and none for `quiet` since: never in the middle of a burst.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>

namespace endorecon::server {

class IdleTrim {
 public:
  using Clock = std::chrono::steady_clock;
  explicit IdleTrim(std::chrono::milliseconds quiet = std::chrono::seconds(2)) : quiet_(quiet) {}

  // Bytes received now (any thread).
  void Received(std::int64_t bytes);
  // Called periodically (one thread): trims when a burst ended at least `quiet` ago; returns
  // whether it trimmed.
  bool Tick(Clock::time_point now);

 private:
  std::chrono::milliseconds quiet_;
  std::atomic<Clock::rep> last_received_{0};  // Clock ticks since its epoch; 0: none since a trim
};

}  // namespace endorecon::server
