// A line of progress on the terminal, rewritten in place ("\r prepared 12/40 frames"), that log
// messages do not run into: a message logged while the line is open starts on a line of its own
// (a warning read "prepared 12/12 frames [warning] ..." on one line, and looked missing; found
// 2026-12-06).
#pragma once

#include <string>

namespace endorecon::worker {

// Rewrites the open line with `text` (opening one if none is). When stderr is no terminal (a pipe, a
// log file), writes `text` as a line of its own instead, at most once every 10 seconds.
void ShowProgress(const std::string& text);
// Ends the open line, if any, with a newline.
void EndProgress();
// Makes spdlog's default logger end the open line before each message. Called once at start.
void EndProgressBeforeEachLog();

}  // namespace endorecon::worker
