// Ctrl-C (or SIGTERM, which job runners send: `timeout`, Python's terminate(), systemd) during a step
// the CLI can pick up again says how, then exits 130 (143 for SIGTERM), as a shell reports them:
// while a job is watched (the job goes on on the server) and while a clip uploads (what arrived is
// kept, and the same submit resumes it). The message is made before the signal can come: the handler
// only writes it. One at a time; the previous handler comes back when the note goes.
#pragma once

#include <signal.h>

#include <string>

namespace endorecon::client {

class InterruptNote {
 public:
  // `message`: what to print on its own line(s) (at most 511 bytes), without "endorecon: ".
  explicit InterruptNote(const std::string& message);
  ~InterruptNote();
  InterruptNote(const InterruptNote&) = delete;
  InterruptNote& operator=(const InterruptNote&) = delete;

 private:
  struct sigaction previous_ {};
  struct sigaction previous_term_ {};
};

}  // namespace endorecon::client
