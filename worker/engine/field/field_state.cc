#include "worker/engine/field/field_state.h"

#include <cstdint>
#include <cstring>
#include <istream>
#include <ostream>
#include <string>

#include "common/error.h"

namespace endorecon::field {
namespace {

constexpr char kMagic[16] = "ENDORECON-FIELD";
constexpr std::uint32_t kFormatVersion = 2;  // 2: blocks named in the stream
constexpr std::uint32_t kMaxNameLength = 64;

template <typename T>
void Put(std::ostream& out, const T& value) {
  out.write(reinterpret_cast<const char*>(&value), sizeof(value));
}

template <typename T>
T Get(std::istream& in, const std::string& where) {
  T value{};
  in.read(reinterpret_cast<char*>(&value), sizeof(value));
  if (!in) Fail(ErrorCode::kDataLoss, "field state: truncated " + where);
  return value;
}

}  // namespace

template <typename S>
void SaveFieldState(const FieldT<S>& field, std::ostream& out) {
  const auto blocks = field.Blocks();
  out.write(kMagic, sizeof(kMagic));
  Put(out, kFormatVersion);
  Put(out, static_cast<std::uint32_t>(sizeof(S)));
  Put(out, static_cast<std::uint32_t>(blocks.size()));
  for (const auto& b : blocks) {
    Put(out, static_cast<std::uint32_t>(b.name.size()));
    out.write(b.name.data(), static_cast<std::streamsize>(b.name.size()));
    Put(out, static_cast<std::uint64_t>(b.size));
    out.write(reinterpret_cast<const char*>(b.value), static_cast<std::streamsize>(b.size * sizeof(S)));
  }
}

template <typename S>
void LoadFieldState(FieldT<S>& field, std::istream& in) {
  char magic[sizeof(kMagic)] = {};
  in.read(magic, sizeof(magic));
  if (!in || std::memcmp(magic, kMagic, sizeof(kMagic)) != 0)
    Fail(ErrorCode::kDataLoss, "field state: not a field state (bad header)");
  const auto version = Get<std::uint32_t>(in, "header");
  const auto scalar = Get<std::uint32_t>(in, "header");
  const auto count = Get<std::uint32_t>(in, "header");
  auto blocks = field.Blocks();
  if (version != kFormatVersion || scalar != sizeof(S) || count != blocks.size()) {
    Fail(ErrorCode::kDataLoss, "field state: format " + std::to_string(version) + ", " +
                                   std::to_string(scalar) + "-byte scalars, " + std::to_string(count) +
                                   " blocks; this field reads format " + std::to_string(kFormatVersion) +
                                   ", " + std::to_string(sizeof(S)) + ", " + std::to_string(blocks.size()) +
                                   (version == kFormatVersion && scalar == sizeof(S)
                                        ? " (a field of another shape: a checkpoint of another clip, or of "
                                          "other field keys, is resumed only on its own)"
                                        : ""));
  }
  for (auto& b : blocks) {
    const auto length = Get<std::uint32_t>(in, "before block '" + b.name + "'");
    if (length > kMaxNameLength)
      Fail(ErrorCode::kDataLoss, "field state: corrupt name before block '" + b.name + "'");
    std::string name(length, '\0');
    in.read(name.data(), length);
    const auto size = Get<std::uint64_t>(in, "before block '" + b.name + "'");
    if (name != b.name || size != b.size) {
      Fail(ErrorCode::kDataLoss, "field state: block '" + name + "' of " + std::to_string(size) +
                                     " values where this field has '" + b.name + "' of " +
                                     std::to_string(b.size) + " (another configuration?)");
    }
    in.read(reinterpret_cast<char*>(b.value), static_cast<std::streamsize>(size * sizeof(S)));
    if (!in) Fail(ErrorCode::kDataLoss, "field state: truncated inside block '" + b.name + "'");
  }
}

template void SaveFieldState(const FieldT<float>&, std::ostream&);
template void SaveFieldState(const FieldT<double>&, std::ostream&);
template void LoadFieldState(FieldT<float>&, std::istream&);
template void LoadFieldState(FieldT<double>&, std::istream&);

}  // namespace endorecon::field
