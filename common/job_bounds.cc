#include "common/job_bounds.h"

#include <algorithm>
#include <string_view>
#include <utility>

#include "common/error.h"
#include "common/safe_path.h"

namespace endorecon {

namespace {

bool IsControl(char c) {
  const auto byte = static_cast<unsigned char>(c);
  return byte < 0x20 || byte == 0x7f;
}

// The bytes of a Unicode control at `at` (0: none): the direction controls U+061C, U+200E, U+200F,
// U+202A-U+202E and U+2066-U+2069 turn the rest of a terminal's line around ("x\u202eevil" is shown
// "xlive"; found 2026-12-06), U+2028 and U+2029 break it, U+FEFF hides, and C1 controls
// (U+0080-U+009F) are escape sequences to some terminals.
std::size_t UnicodeControlAt(std::string_view text, std::size_t at) {
  const auto byte = [&](std::size_t i) { return static_cast<unsigned char>(text[at + i]); };
  if (at + 1 < text.size() && byte(0) == 0xC2 && byte(1) >= 0x80 && byte(1) <= 0x9F) return 2;
  if (at + 1 < text.size() && byte(0) == 0xD8 && byte(1) == 0x9C) return 2;
  if (at + 2 >= text.size()) return 0;
  if (byte(0) == 0xEF) return byte(1) == 0xBB && byte(2) == 0xBF ? 3 : 0;
  if (byte(0) != 0xE2) return 0;
  const bool marks =
      byte(1) == 0x80 && (byte(2) == 0x8E || byte(2) == 0x8F || (byte(2) >= 0xA8 && byte(2) <= 0xAE));
  const bool isolates = byte(1) == 0x81 && byte(2) >= 0xA6 && byte(2) <= 0xA9;
  return marks || isolates ? 3 : 0;
}

// `text` is printed in listings and terminals: no control character, at most `most` bytes.
void CheckPrintable(const std::string& text, std::size_t most, const std::string& what) {
  if (text.size() > most) {
    FailInvalid(what + " has " + std::to_string(text.size()) + " bytes; at most " + std::to_string(most));
  }
  for (std::size_t i = 0; i < text.size(); ++i) {
    if (IsControl(text[i])) {
      FailInvalid(what + " holds a control character (byte " +
                  std::to_string(static_cast<unsigned char>(text[i])) +
                  "); it is printed in listings and terminals");
    }
    if (UnicodeControlAt(text, i) > 0) {
      FailInvalid(what + " holds a Unicode control character (at byte " + std::to_string(i) +
                  "): it would turn a terminal's text around; it is printed in listings and terminals");
    }
  }
}

}  // namespace

std::string PrintableText(std::string text, std::size_t most) {
  const bool utf8 = IsUtf8(text);
  std::string out;
  out.reserve(text.size());
  for (std::size_t i = 0; i < text.size(); ++i) {
    const std::size_t control = utf8 ? UnicodeControlAt(text, i) : 0;
    if (control > 0) {
      out += '?';
      i += control - 1;
    } else if (IsControl(text[i]) || (!utf8 && static_cast<unsigned char>(text[i]) >= 0x80)) {
      out += '?';
    } else {
      out += text[i];
    }
  }
  if (out.size() > most) {
    std::size_t end = most;
    while (end > 0 && (static_cast<unsigned char>(out[end]) & 0xC0) == 0x80) --end;  // not mid-character
    out.resize(end);
  }
  return out;
}

std::string PrintableLines(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  for (std::size_t start = 0; start <= text.size();) {
    const std::size_t end = std::min(text.find('\n', start), text.size());
    out += PrintableText(std::string(text.substr(start, end - start)), end - start);
    if (end == text.size()) break;
    out += '\n';
    start = end + 1;
  }
  return out;
}

void ValidateJobName(const std::string& name) {
  CheckPrintable(name, kMaxJobNameBytes, "name");
  // Listed as a blank and titling a report "endorecon report:    " (found 2026-12-06).
  if (!name.empty() && name.find_first_not_of(" \t") == std::string::npos)
    FailInvalid("name is only spaces: give a name, or none (the clip's is taken)");
}

std::string ValidJobName(std::string name) { return PrintableText(std::move(name), kMaxJobNameBytes); }

std::string PathName(const std::filesystem::path& path) {
  std::error_code failed;
  const std::filesystem::path absolute = std::filesystem::absolute(path, failed);
  const std::filesystem::path normal = (failed ? path : absolute).lexically_normal();
  const std::filesystem::path name =
      normal.has_filename() ? normal.filename() : normal.parent_path().filename();
  return name.empty() ? normal.string() : name.string();
}

void ValidateWorkerId(const std::string& id) {
  if (id.empty()) FailInvalid("worker id is empty");
  CheckPrintable(id, kMaxWorkerIdBytes, "worker id");
}

void ValidatePriority(int priority) {
  if (priority < -kMaxPriority || priority > kMaxPriority) {
    FailInvalid("priority is " + std::to_string(priority) + "; expected " + std::to_string(-kMaxPriority) +
                " to " + std::to_string(kMaxPriority));
  }
}

}  // namespace endorecon
