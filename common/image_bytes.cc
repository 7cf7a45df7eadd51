#include "common/image_bytes.h"

#include <array>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <string>
#include <string_view>

#include "common/error.h"

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

// Walks the chunks after the signature: length (4 bytes, big-endian), type (4), data, CRC (4).
void CheckPngChunks(const fs::path& path, std::ifstream& in, std::uint64_t size) {
  std::uint64_t offset = kPngSignature.size();
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
    if (name == "IEND") return;
    offset = end;
  }
}

}  // namespace

void CheckImageBytes(const fs::path& path) {
  std::error_code error;
  if (!fs::is_regular_file(path, error)) FailInvalid(path.string() + ": file does not exist");
  std::ifstream in(path, std::ios::binary);
  if (!in) FailInvalid(path.string() + ": cannot open the file");
  char head[8] = {};
  in.read(head, sizeof(head));
  const std::string_view bytes(head, static_cast<std::size_t>(in.gcount()));
  if (StartsWith(bytes, kPngSignature)) {
    in.clear();
    CheckPngChunks(path, in, fs::file_size(path));
    return;
  }
  for (const std::string_view magic : {std::string_view("\xff\xd8\xff", 3), std::string_view("BM", 2),
                                       std::string_view("II*\0", 4), std::string_view("MM\0*", 4)}) {
    if (StartsWith(bytes, magic)) return;
  }
  FailInvalid(path.string() + ": not a PNG, JPEG, BMP or TIFF image");
}

}  // namespace endorecon
