#include "server/wal_check.h"

#include <array>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

#include "common/error.h"
#include "common/file_read.h"
#include "server/access_failure.h"

namespace endorecon::server {
namespace {

constexpr std::uint32_t kMagicLittleEndian = 0x377f0682;  // checksums of little-endian words
constexpr std::uint32_t kMagicBigEndian = 0x377f0683;     // of big-endian words
constexpr std::size_t kHeaderBytes = 32, kFrameHeaderBytes = 24;

std::uint32_t BigEndian(const unsigned char* bytes) {
  return (std::uint32_t{bytes[0]} << 24) | (std::uint32_t{bytes[1]} << 16) | (std::uint32_t{bytes[2]} << 8) |
         std::uint32_t{bytes[3]};
}

// SQLite's checksum: over 32-bit words x (in the log's byte order), s0 += x[i] + s1; s1 += x[i+1] + s0,
// from the seed (s0, s1); `size` a multiple of 8.
std::array<std::uint32_t, 2> Checksum(const unsigned char* data, std::size_t size, bool big_endian,
                                      std::array<std::uint32_t, 2> seed) {
  const auto word = [&](std::size_t at) {
    std::uint32_t value = BigEndian(data + at);
    if (!big_endian) value = __builtin_bswap32(value);
    return value;
  };
  auto [s0, s1] = seed;
  for (std::size_t at = 0; at + 8 <= size; at += 8) {
    s0 += word(at) + s1;
    s1 += word(at + 4) + s0;
  }
  return {s0, s1};
}

}  // namespace

std::optional<WalDamage> FindWalDamage(const std::filesystem::path& wal) {
  std::error_code error;
  if (!std::filesystem::is_regular_file(wal, error)) return std::nullopt;
  std::ifstream in(wal, std::ios::binary);
  if (!in) FailAccess(wal.string() + ": cannot be read", errno);
  std::array<unsigned char, kHeaderBytes> header{};
  if (!in.read(reinterpret_cast<char*>(header.data()), header.size())) return std::nullopt;
  const std::uint32_t magic = BigEndian(header.data());
  if (magic != kMagicLittleEndian && magic != kMagicBigEndian) return std::nullopt;
  const bool big_endian = magic == kMagicBigEndian;
  const std::uint32_t page_size = BigEndian(header.data() + 8);
  if (page_size < 512 || page_size > 65536 || (page_size & (page_size - 1)) != 0) return std::nullopt;
  const std::uint32_t salt[2] = {BigEndian(header.data() + 16), BigEndian(header.data() + 20)};
  const std::array<std::uint32_t, 2> stored_header = {BigEndian(header.data() + 24), BigEndian(header.data() + 28)};

  std::optional<WalDamage> damage;
  if (Checksum(header.data(), 24, big_endian, {0, 0}) != stored_header) damage = WalDamage{-1, 0};
  // Each frame's checksum runs on from the one before: from the stored one, so that the frames after
  // a damaged one are verified on their own.
  std::array<std::uint32_t, 2> previous = stored_header;
  std::vector<unsigned char> frame(kFrameHeaderBytes + page_size);
  for (std::int64_t index = 0; in.read(reinterpret_cast<char*>(frame.data()), static_cast<std::streamsize>(frame.size()));
       ++index) {
    if (BigEndian(frame.data() + 8) != salt[0] || BigEndian(frame.data() + 12) != salt[1]) break;  // an older log's
    const std::array<std::uint32_t, 2> stored = {BigEndian(frame.data() + 16), BigEndian(frame.data() + 20)};
    auto sum = Checksum(frame.data(), 8, big_endian, previous);
    sum = Checksum(frame.data() + kFrameHeaderBytes, page_size, big_endian, sum);
    const bool commit = BigEndian(frame.data() + 4) != 0;
    if (sum != stored) {
      if (!damage) damage = WalDamage{index, 0};
    } else if (damage && commit) {
      ++damage->commits_after;
    }
    previous = stored;
  }
  if (damage && damage->commits_after > 0) return damage;
  return std::nullopt;
}

}  // namespace endorecon::server
