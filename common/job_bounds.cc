#include "common/job_bounds.h"

#include "common/error.h"

namespace endorecon {

void ValidateJobName(const std::string& name) {
  if (name.size() > kMaxJobNameBytes) {
    FailInvalid("name has " + std::to_string(name.size()) + " bytes; at most " +
                std::to_string(kMaxJobNameBytes));
  }
  for (const char c : name) {
    const auto byte = static_cast<unsigned char>(c);
    if (byte < 0x20 || byte == 0x7f) {
      FailInvalid("name holds a control character (byte " + std::to_string(byte) +
                  "); a job's name is printed in listings and terminals");
    }
  }
}

void ValidatePriority(int priority) {
  if (priority < -kMaxPriority || priority > kMaxPriority) {
    FailInvalid("priority is " + std::to_string(priority) + "; expected " + std::to_string(-kMaxPriority) +
                " to " + std::to_string(kMaxPriority));
  }
}

}  // namespace endorecon
