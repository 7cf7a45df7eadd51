#include "common/job_bounds.h"

#include "common/error.h"
#include "common/safe_path.h"

namespace endorecon {

namespace {

bool IsControl(char c) {
  const auto byte = static_cast<unsigned char>(c);
  return byte < 0x20 || byte == 0x7f;
}

// `text` is printed in listings and terminals: no control character, at most `most` bytes.
void CheckPrintable(const std::string& text, std::size_t most, const std::string& what) {
  if (text.size() > most) {
    FailInvalid(what + " has " + std::to_string(text.size()) + " bytes; at most " + std::to_string(most));
  }
  for (const char c : text) {
    if (IsControl(c)) {
      FailInvalid(what + " holds a control character (byte " + std::to_string(static_cast<unsigned char>(c)) +
                  "); it is printed in listings and terminals");
    }
  }
}

}  // namespace

void ValidateJobName(const std::string& name) { CheckPrintable(name, kMaxJobNameBytes, "name"); }

std::string ValidJobName(std::string name) {
  const bool utf8 = IsUtf8(name);
  for (char& c : name) {
    if (IsControl(c) || (!utf8 && static_cast<unsigned char>(c) >= 0x80)) c = '?';
  }
  if (name.size() > kMaxJobNameBytes) {
    std::size_t end = kMaxJobNameBytes;
    while (end > 0 && (static_cast<unsigned char>(name[end]) & 0xC0) == 0x80) --end;  // not mid-character
    name.resize(end);
  }
  return name;
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
