#include "common/image_bytes.h"

#include <zlib.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <string>
#include <string_view>
#include <vector>

#include "common/error.h"
#include "common/file_read.h"
#include "common/jpeg_header.h"

namespace endorecon {
namespace {

namespace fs = std::filesystem;

constexpr std::string_view kPngSignature("\x89PNG\r\n\x1a\n", 8);
// PNG limits a chunk's length to 2^31 - 1 (PNG specification, 5.3).
constexpr std::uint64_t kMostPngChunkLength = 0x7fffffff;

bool StartsWith(std::string_view bytes, std::string_view magic) {
  return bytes.substr(0, magic.size()) == magic;
}

std::uint32_t BigEndian32(const unsigned char* bytes) {
  return (std::uint32_t{bytes[0]} << 24) | (std::uint32_t{bytes[1]} << 16) | (std::uint32_t{bytes[2]} << 8) |
         std::uint32_t{bytes[3]};
}

// A chunk type as text for messages: its four letters, or its bytes in hex when they are not letters.
std::string ChunkName(const unsigned char* type) {
  std::string name;
  for (int i = 0; i < 4; ++i) {
    const unsigned char c = type[i];
    if ((c < 'A' || c > 'Z') && (c < 'a' || c > 'z')) {
      char hex[16];
      std::snprintf(hex, sizeof(hex), "%02x%02x%02x%02x", type[0], type[1], type[2], type[3]);
      return std::string("0x") + hex;
    }
    name += static_cast<char>(c);
  }
  return name;
}

// Walks the chunks after the signature: length (4 bytes, big-endian), type (4), data, CRC (4). Each
// chunk's CRC (over its type and data, zlib's crc32 as PNG specifies) is checked: a damaged byte was
// reported by the decoder only as "cannot decode the image", libpng's reason going to stderr.
void CheckPngChunks(const fs::path& path, std::ifstream& in, std::uint64_t size) {
  std::uint64_t offset = kPngSignature.size();
  std::vector<char> block(1 << 16);
  while (true) {
    std::array<unsigned char, 8> header{};
    in.seekg(static_cast<std::streamoff>(offset));
    in.read(reinterpret_cast<char*>(header.data()), header.size());
    if (static_cast<std::size_t>(in.gcount()) < header.size()) {
      FailInvalid(path.string() + ": a truncated PNG: it ends at byte " + std::to_string(size) +
                  " before its IEND chunk (an interrupted copy or upload?)");
    }
    const std::uint64_t length = BigEndian32(header.data());
    const std::string name = ChunkName(header.data() + 4);
    // Not four letters: no chunk begins here. A file padded with zeros (what an interrupted,
    // preallocated copy leaves) was walked in 12-byte steps to its end: 2 GB took minutes.
    if (name.starts_with("0x")) {
      FailInvalid(path.string() + ": a damaged PNG: at byte " + std::to_string(offset) +
                  ", where a chunk should begin, its type is " + name +
                  ", not four letters (a corrupt file, or one padded after an interrupted copy?)");
    }
    if (length > kMostPngChunkLength) {
      FailInvalid(path.string() + ": a damaged PNG: its chunk " + name + " at byte " +
                  std::to_string(offset) + " declares " + std::to_string(length) +
                  " bytes, more than PNG allows");
    }
    const std::uint64_t end = offset + 12 + length;
    if (end > size) {
      FailInvalid(path.string() + ": a truncated PNG: its chunk " + name + " at byte " +
                  std::to_string(offset) + " needs " + std::to_string(end) + " bytes, the file has " +
                  std::to_string(size) + " (an interrupted copy or upload?)");
    }
    uLong crc = crc32(0L, header.data() + 4, 4);
    for (std::uint64_t left = length; left > 0;) {
      const auto want = static_cast<std::streamsize>(std::min<std::uint64_t>(left, block.size()));
      in.read(block.data(), want);
      if (in.gcount() != want) FailInvalid(path.string() + ": cannot read its chunk " + name);
      crc = crc32(crc, reinterpret_cast<const Bytef*>(block.data()), static_cast<uInt>(want));
      left -= static_cast<std::uint64_t>(want);
    }
    std::array<unsigned char, 4> stored{};
    in.read(reinterpret_cast<char*>(stored.data()), stored.size());
    if (static_cast<std::size_t>(in.gcount()) < stored.size() || BigEndian32(stored.data()) != crc) {
      FailInvalid(path.string() + ": a damaged PNG: its chunk " + name + " at byte " +
                  std::to_string(offset) + " fails its CRC check (a corrupt copy or upload?)");
    }
    if (name == "IEND") return;
    offset = end;
  }
}

// A JPEG whose scan has no end-of-image marker after it was cut short: libjpeg decodes it with a
// warning on stderr and grey below the cut (found 2026-12-05). The header is walked to the first
// scan (SOS) by its segments' lengths (an Exif thumbnail's own EOI inside APP1 is skipped); after it,
// in entropy-coded data a 0xFF byte is always followed by 0x00 or a marker, so the next FF D9 is the
// image's end. A header the walk cannot follow is left to the decoder.
void CheckJpegEnd(const fs::path& path, std::ifstream& in) {
  in.seekg(0);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const auto* data = reinterpret_cast<const unsigned char*>(bytes.data());
  const auto scan =
      FindJpegHeaderMarker(data, bytes.size(), [](unsigned char marker) { return marker == 0xDA; });
  if (!scan) return;
  const std::size_t length = std::size_t{data[*scan + 2]} << 8 | data[*scan + 3];
  if (bytes.find("\xFF\xD9", *scan + 2 + length) == std::string::npos) {
    FailInvalid(path.string() + ": a truncated JPEG: no end-of-image marker after its scan, which " +
                "starts at byte " + std::to_string(*scan) + " of " + std::to_string(bytes.size()) +
                " (an interrupted copy or upload?)");
  }
}

}  // namespace

std::optional<ImageSize> ImageSizeOf(const fs::path& path) {
  std::ifstream in = OpenToRead(path);
  std::vector<unsigned char> head(std::size_t{1} << 20);
  in.read(reinterpret_cast<char*>(head.data()), static_cast<std::streamsize>(head.size()));
  head.resize(static_cast<std::size_t>(in.gcount()));
  const std::string_view bytes(reinterpret_cast<const char*>(head.data()), head.size());
  const auto positive = [](std::int64_t width, std::int64_t height) -> std::optional<ImageSize> {
    if (width <= 0 || height <= 0 || width > 1 << 30 || height > 1 << 30) return std::nullopt;
    return ImageSize{static_cast<int>(width), static_cast<int>(height)};
  };
  if (StartsWith(bytes, kPngSignature) && head.size() >= 24 && bytes.substr(12, 4) == "IHDR")
    return positive(BigEndian32(&head[16]), BigEndian32(&head[20]));
  if (StartsWith(bytes, "BM") && head.size() >= 26) {
    const auto little16 = [&](std::size_t at) {
      return std::int64_t{head[at]} | std::int64_t{head[at + 1]} << 8;
    };
    const auto little32 = [&](std::size_t at) {
      return static_cast<std::int32_t>(std::uint32_t{head[at]} | std::uint32_t{head[at + 1]} << 8 |
                                       std::uint32_t{head[at + 2]} << 16 | std::uint32_t{head[at + 3]} << 24);
    };
    if (little32(14) == 12) return positive(little16(18), little16(20));  // BITMAPCOREHEADER
    return positive(little32(18), std::abs(std::int64_t{little32(22)}));  // height < 0: top-down rows
  }
  if (StartsWith(bytes, std::string_view("\xff\xd8\xff", 3))) {
    // Start of frame: SOF0-3, 5-7, 9-11, 13-15 (C4 is DHT, C8 JPG, CC DAC): FF Cn, length, precision,
    // height, width.
    const auto frame = FindJpegHeaderMarker(head.data(), head.size(), [](unsigned char marker) {
      return marker >= 0xc0 && marker <= 0xcf && marker != 0xc4 && marker != 0xc8 && marker != 0xcc;
    });
    if (!frame || *frame + 9 > head.size()) return std::nullopt;
    const unsigned char* sof = head.data() + *frame;
    return positive(std::int64_t{sof[7]} << 8 | sof[8], std::int64_t{sof[5]} << 8 | sof[6]);  // X, then Y
  }
  return std::nullopt;
}

void CheckImageBytes(const fs::path& path) {
  std::error_code error;
  if (!fs::is_regular_file(path, error)) FailInvalid(path.string() + ": file does not exist");
  std::ifstream in = OpenToRead(path);
  char head[8] = {};
  in.read(head, sizeof(head));
  const std::string_view bytes(head, static_cast<std::size_t>(in.gcount()));
  if (bytes.empty()) FailInvalid(path.string() + ": an empty file (0 bytes), not an image");
  if (StartsWith(bytes, kPngSignature)) {
    in.clear();
    CheckPngChunks(path, in, fs::file_size(path));
    return;
  }
  if (StartsWith(bytes, std::string_view("\xff\xd8\xff", 3))) {
    in.clear();
    CheckJpegEnd(path, in);
    return;
  }
  for (const std::string_view magic :
       {std::string_view("BM", 2), std::string_view("II*\0", 4), std::string_view("MM\0*", 4)}) {
    if (StartsWith(bytes, magic)) return;
  }
  FailInvalid(path.string() + ": not a PNG, JPEG, BMP or TIFF image");
}

}  // namespace endorecon
