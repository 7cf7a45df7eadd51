#include "common/safe_path.h"

#include <cstdint>
#include <string>

#include "common/error.h"

namespace endorecon {
namespace {

[[noreturn]] void Reject(std::string_view path, const char* why) {
  std::string message("file path '");
  message.append(path.substr(0, 256));
  message.append("' ");
  message.append(why);
  FailInvalid(message);
}

// The path with every byte that is not printable ASCII as \xNN, for a message about its name.
std::string Escaped(std::string_view path) {
  std::string out;
  for (const char ch : path.substr(0, 256)) {
    const auto c = static_cast<unsigned char>(ch);
    if (c >= 0x20 && c < 0x7F) {
      out += ch;
    } else {
      static constexpr char kHex[] = "0123456789abcdef";
      out += "\\x";
      out += kHex[c >> 4];
      out += kHex[c & 15];
    }
  }
  return out;
}

}  // namespace

// Written out: the few lines no library here offers without its internals (protobuf's check is
// internal).
bool IsUtf8(std::string_view text) {
  std::size_t i = 0;
  while (i < text.size()) {
    const auto c = static_cast<unsigned char>(text[i]);
    std::size_t extra = 0;
    std::uint32_t low = 0, code = 0;
    if (c < 0x80) {
      ++i;
      continue;
    } else if (c >= 0xC2 && c <= 0xDF) {
      extra = 1, low = 0x80, code = c & 0x1F;
    } else if (c >= 0xE0 && c <= 0xEF) {
      extra = 2, low = 0x800, code = c & 0x0F;
    } else if (c >= 0xF0 && c <= 0xF4) {
      extra = 3, low = 0x10000, code = c & 0x07;
    } else {
      return false;
    }
    if (i + extra >= text.size()) return false;  // cut short
    for (std::size_t k = 1; k <= extra; ++k) {
      const auto next = static_cast<unsigned char>(text[i + k]);
      if ((next & 0xC0) != 0x80) return false;
      code = code << 6 | (next & 0x3F);
    }
    if (code < low || code > 0x10FFFF || (code >= 0xD800 && code <= 0xDFFF)) return false;
    i += extra + 1;
  }
  return true;
}

void CheckRelativePath(std::string_view path) {
  if (path.empty()) Reject(path, "is empty");
  if (path.size() > 4096) Reject(path, "is longer than 4096 bytes");
  if (path.front() == '/') Reject(path, "is absolute; paths must be relative to the upload");
  if (path.find('\\') != std::string_view::npos || path.find('\0') != std::string_view::npos) {
    Reject(path, "contains a backslash or NUL");
  }
  // Names travel as protobuf strings, which must be UTF-8: another name failed the upload query with
  // an empty INTERNAL error (found 2026-12-05).
  if (!IsUtf8(path)) {
    FailInvalid("file path '" + Escaped(path) +
                "' is not UTF-8 text (the service carries names as UTF-8); rename it");
  }
  std::size_t start = 0;
  while (start <= path.size()) {
    const std::size_t end = std::min(path.find('/', start), path.size());
    const std::string_view segment = path.substr(start, end - start);
    if (segment.empty() || segment == "." || segment == "..")
      Reject(path, "has an empty, '.' or '..' segment");
    start = end + 1;
  }
}

}  // namespace endorecon
