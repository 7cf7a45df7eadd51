#include "client/interrupt_note.h"

#include <unistd.h>

#include <algorithm>
#include <cstdio>

namespace endorecon::client {
namespace {

char interrupt_message[512];
std::size_t interrupt_length = 0;

extern "C" void OnInterrupt(int signal) {
  (void)!::write(STDERR_FILENO, interrupt_message, interrupt_length);
  ::_exit(128 + signal);  // 130 for SIGINT, 143 for SIGTERM, as a shell reports them
}

}  // namespace

InterruptNote::InterruptNote(const std::string& message) {
  // The leading newline ends a progress line on a terminal (^C leaves the cursor after it); in a log it
  // was a blank line (found 2026-12-07).
  const char* start = ::isatty(STDERR_FILENO) ? "\n" : "";
  const int n = std::snprintf(interrupt_message, sizeof(interrupt_message), "%sendorecon: %s\n", start,
                              message.c_str());
  interrupt_length = n > 0 ? std::min(static_cast<std::size_t>(n), sizeof(interrupt_message) - 1) : 0;
  struct sigaction action {};
  action.sa_handler = OnInterrupt;
  sigemptyset(&action.sa_mask);
  ::sigaction(SIGINT, &action, &previous_);
  ::sigaction(SIGTERM, &action, &previous_term_);
}

InterruptNote::~InterruptNote() {
  ::sigaction(SIGINT, &previous_, nullptr);
  ::sigaction(SIGTERM, &previous_term_, nullptr);
}

}  // namespace endorecon::client
