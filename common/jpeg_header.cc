#include "common/jpeg_header.h"

namespace endorecon {

std::optional<std::size_t> FindJpegHeaderMarker(const unsigned char* data, std::size_t size,
                                                bool (*stop)(unsigned char marker)) {
  std::size_t at = 2;  // after SOI
  while (at + 4 <= size) {
    if (data[at] != 0xFF) return std::nullopt;
    const unsigned char marker = data[at + 1];
    if (marker == 0xFF) {  // a fill byte
      ++at;
      continue;
    }
    if (stop(marker)) return at;
    if (marker == 0x00 || marker == 0x01 || (marker >= 0xD0 && marker <= 0xD9)) return std::nullopt;
    const std::size_t length = std::size_t{data[at + 2]} << 8 | data[at + 3];
    if (length < 2) return std::nullopt;
    at += 2 + length;
  }
  return std::nullopt;
}

}  // namespace endorecon
