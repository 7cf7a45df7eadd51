// Paces the audit lines of refused calls. One client with a wrong token in a loop had 2,000 calls
// refused in 1.5 s and wrote 308 kB to the audit log (about 18 GB a day, on the data disk) without
// ever holding a token (found 2026-12-07). Refusals alike (the same principal, caller address with
// its port aside, method and outcome) get a line each up to `burst` per window; past it they are
// held back and counted, and the line that ends the hold says how many it stands for (held_back),
// so lines plus held_back count every refusal. That line is the next refusal's after the window, or
// the one TakeDue writes once the window is over (the server's maintenance thread asks each second).
// A flood then costs at most burst + 1 lines a window for each kind. Thread-safe.
#pragma once

#include <chrono>
#include <map>
#include <mutex>
#include <string>
#include <vector>

#include "server/audit_log.h"

namespace endorecon::server {

class RefusalPacer {
 public:
  using Clock = std::chrono::steady_clock;
  RefusalPacer(Clock::duration window, int burst) : window_(window), burst_(burst) {}

  // Whether the refusal `entry` (at `now`) gets its line now; if so, sets its held_back.
  bool Pass(AuditEntry& entry, Clock::time_point now);
  // The lines owed for kinds whose window with refusals held back is over: each the kind's latest
  // refusal, its held_back the others.
  std::vector<AuditEntry> TakeDue(Clock::time_point now);

 private:
  struct Kind {
    Clock::time_point window_start;
    int lines = 0;       // written in this window
    long long held = 0;  // held back in this window
    AuditEntry latest;   // the latest held back
  };
  // Kinds known at most; past it (a flood from very many addresses) refusals of new kinds are written
  // unpaced rather than held in memory without bound.
  static constexpr std::size_t kMostKinds = 10000;

  Clock::duration window_;
  int burst_;
  std::mutex mutex_;
  std::map<std::string, Kind> kinds_;
};

}  // namespace endorecon::server
