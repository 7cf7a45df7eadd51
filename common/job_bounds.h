// Bounds on what a client names in a submit, checked by the server on every Submit and by the CLI
// before it uploads a byte: a job's name is shown in every listing and terminal, its config is
// stored with the job, and a priority orders the one queue every tenant shares.
#pragma once

#include <cstddef>
#include <filesystem>
#include <string>
#include <string_view>

namespace endorecon {

inline constexpr std::size_t kMaxJobNameBytes = 256;
inline constexpr std::size_t kMaxConfigBytes = 64 * 1024;
inline constexpr int kMaxPriority = 100;
// A time budget is 0 (none) or at least this many seconds: loading a clip and writing its results take
// seconds, and a budget of 0.001 or 5 is a unit slip (milliseconds, minutes), not a plan.
inline constexpr double kLeastTimeBudgetS = 10;
// ... and at most a week: a larger one is a unit slip too (1e300 ran without end, its ETA overflowing).
inline constexpr double kMostTimeBudgetS = 7 * 24 * 3600;

// Throws Error(kInvalidArgument) for a name over kMaxJobNameBytes or holding a control character
// (ASCII or C1, or a Unicode direction control), or of spaces alone.
void ValidateJobName(const std::string& name);
// Text a terminal may show as it is: control characters (as ValidateJobName's) and bytes of no UTF-8
// text as '?', cut to `most` bytes on a character's end. For text the server passes on from a worker
// (a failure's reason, a device's description) and names made from what no one chose as a name.
std::string PrintableText(std::string text, std::size_t most);
// PrintableText of each line, the line breaks kept, uncut: what a command prints of an error, which
// repeats what it was given (`endorecon status "$(printf 'a\x1b[2Jb')"` cleared the terminal; found
// 2026-12-06).
std::string PrintableLines(std::string_view text);
// A name made from what the user did not choose as a name (a clip's folder name), made valid:
// PrintableText cut to kMaxJobNameBytes.
std::string ValidJobName(std::string name);
// What the last part of `path` names (a clip folder, a recording, a results folder), of its absolute,
// normal form: "clips/c12/" and "." name their folder (a job and a report were named "" and "."); the
// root names itself.
std::string PathName(const std::filesystem::path& path);
// A worker's id is listed by `endorecon workers` as a job's name is: the same rules, at most
// kMaxWorkerIdBytes, not empty.
inline constexpr std::size_t kMaxWorkerIdBytes = 128;
void ValidateWorkerId(const std::string& id);
// A worker's reason for a failure is kept (and shown) up to this many bytes.
inline constexpr std::size_t kMaxFailureReasonBytes = 8192;
// Throws Error(kInvalidArgument) unless -kMaxPriority <= priority <= kMaxPriority.
void ValidatePriority(int priority);

}  // namespace endorecon
