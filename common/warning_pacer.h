// When a warning that repeats (a call retried every second while a server is away) is due in the
// log: the first time, then at most once every `every`, saying how many repeats were held back. A
// line a second for a 14 s outage was noise that hid the one line that mattered.
#pragma once

#include <chrono>

namespace endorecon {

class WarningPacer {
 public:
  explicit WarningPacer(std::chrono::steady_clock::duration every = std::chrono::seconds(30)) : every_(every) {}

  // The next warning is due at once (the trouble ended, or another began).
  void Reset() {
    logged_ = false;
    held_ = 0;
  }

  // Whether repeats were held back and their line's time has come with no repeat to carry their
  // count: the caller logs that count now (`held`). Without it, the count of a burst's end was never
  // said (found 2026-12-07).
  bool Overdue(int& held) {
    const auto now = std::chrono::steady_clock::now();
    if (held_ == 0 || now < next_) return false;
    next_ = now + every_;
    held = held_;
    held_ = 0;
    return true;
  }

  // Whether to log now; when so, `held` is set to the repeats not logged since the last line.
  bool Due(int& held) {
    const auto now = std::chrono::steady_clock::now();
    if (logged_ && now < next_) {
      ++held_;
      return false;
    }
    logged_ = true;
    next_ = now + every_;
    held = held_;
    held_ = 0;
    return true;
  }

 private:
  std::chrono::steady_clock::duration every_;
  std::chrono::steady_clock::time_point next_{};
  bool logged_ = false;
  int held_ = 0;
};

}  // namespace endorecon
