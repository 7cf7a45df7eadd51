#include "common/dicom/uid.h"

#include <dcmtk/dcmdata/dcuid.h>
#include <openssl/rand.h>

#include <array>
#include <cstdint>

#include "common/error.h"

namespace endorecon::dicom {
namespace {

bool ValidComponents(const std::string& text) {
  if (text.empty() || text.front() == '.' || text.back() == '.') return false;
  std::size_t start = 0;
  while (start <= text.size()) {
    const std::size_t end = std::min(text.find('.', start), text.size());
    if (end == start) return false;
    for (std::size_t i = start; i < end; ++i) {
      if (text[i] < '0' || text[i] > '9') return false;
    }
    if (text[start] == '0' && end - start > 1) return false;
    start = end + 1;
  }
  return true;
}

// 128 random bits as a decimal number: repeated division of a big-endian byte string by 10.
std::string RandomDecimal128() {
  std::array<unsigned char, 16> bytes{};
  if (RAND_bytes(bytes.data(), static_cast<int>(bytes.size())) != 1) {
    Fail(ErrorCode::kInternal, "no random bytes for a UID");
  }
  std::string digits;
  bool nonzero = true;
  while (nonzero) {
    unsigned remainder = 0;
    nonzero = false;
    for (auto& byte : bytes) {
      const unsigned value = remainder * 256 + byte;
      byte = static_cast<unsigned char>(value / 10);
      remainder = value % 10;
      nonzero = nonzero || byte != 0;
    }
    digits.insert(digits.begin(), static_cast<char>('0' + remainder));
  }
  return digits;
}

}  // namespace

void CheckUid(const std::string& uid, const std::string& what) {
  if (uid.size() > 64 || !ValidComponents(uid)) {
    FailInvalid(what + " '" + uid +
                "' is not a DICOM UID (digits in dot-separated components, no leading zeros, at most 64 "
                "characters)");
  }
}

std::string NewUid(const std::string& root) {
  if (root.empty()) return "2.25." + RandomDecimal128();
  if (root.size() > 40 || !ValidComponents(root)) {
    FailInvalid("UID root '" + root +
                "' is not a valid prefix (digits in dot-separated components, no leading zeros, at most 40 "
                "characters)");
  }
  char uid[100];
  dcmGenerateUniqueIdentifier(uid, root.c_str());
  return uid;
}

}  // namespace endorecon::dicom
