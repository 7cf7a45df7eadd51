#include "common/npy.h"

#include <bit>
#include <cctype>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>

#include "common/error.h"
#include "common/file_read.h"

namespace endorecon {
namespace {

static_assert(std::endian::native == std::endian::little, "the .npy reader assumes a little-endian host");

constexpr char kMagic[] = "\x93NUMPY";
constexpr std::size_t kMagicSize = 6;

std::string ShapeText(const std::vector<std::size_t>& shape) {
  std::string text = "(";
  for (std::size_t i = 0; i < shape.size(); ++i) {
    if (i > 0) text += ", ";
    text += std::to_string(shape[i]);
  }
  return text + (shape.size() == 1 ? ",)" : ")");
}

// The header is a Python dict literal, e.g. {'descr': '<f8', 'fortran_order': False, 'shape': (63, 17), }.
// Written by hand because no Debian library parses it; only the three keys NumPy writes are allowed.
class HeaderParser {
 public:
  HeaderParser(const std::string& text, const std::filesystem::path& path) : text_(text), path_(path) {}

  void Parse(std::string& descr, bool& fortran_order, std::vector<std::size_t>& shape) {
    bool have_descr = false, have_order = false, have_shape = false;
    Expect('{');
    while (!Accept('}')) {
      const std::string key = QuotedString();
      Expect(':');
      if (key == "descr") {
        descr = QuotedString();
        have_descr = true;
      } else if (key == "fortran_order") {
        fortran_order = Boolean();
        have_order = true;
      } else if (key == "shape") {
        shape = Tuple();
        have_shape = true;
      } else {
        Bad("unexpected key '" + key + "'");
      }
      if (!Accept(',')) {
        Expect('}');
        break;
      }
    }
    if (!have_descr || !have_order || !have_shape) Bad("missing 'descr', 'fortran_order' or 'shape'");
  }

 private:
  [[noreturn]] void Bad(const std::string& what) const {
    FailInvalid(path_.string() + ": bad .npy header (" + what + " at offset " + std::to_string(pos_) +
                "): " + text_);
  }
  void SkipSpace() {
    while (pos_ < text_.size() && std::isspace(static_cast<unsigned char>(text_[pos_]))) ++pos_;
  }
  bool Accept(char c) {
    SkipSpace();
    if (pos_ < text_.size() && text_[pos_] == c) {
      ++pos_;
      return true;
    }
    return false;
  }
  void Expect(char c) {
    if (!Accept(c)) Bad(std::string("expected '") + c + "'");
  }
  std::string QuotedString() {
    SkipSpace();
    if (pos_ >= text_.size() || (text_[pos_] != '\'' && text_[pos_] != '"')) Bad("expected a quoted string");
    const char quote = text_[pos_++];
    const std::size_t end = text_.find(quote, pos_);
    if (end == std::string::npos) Bad("unterminated string");
    std::string value = text_.substr(pos_, end - pos_);
    pos_ = end + 1;
    return value;
  }
  bool Boolean() {
    SkipSpace();
    for (const auto& [word, value] : {std::pair{"True", true}, std::pair{"False", false}}) {
      const std::size_t n = std::strlen(word);
      if (text_.compare(pos_, n, word) == 0) {
        pos_ += n;
        return value;
      }
    }
    Bad("expected True or False");
  }
  std::vector<std::size_t> Tuple() {
    std::vector<std::size_t> values;
    Expect('(');
    while (!Accept(')')) {
      SkipSpace();
      std::size_t value = 0;
      const std::size_t start = pos_;
      while (pos_ < text_.size() && std::isdigit(static_cast<unsigned char>(text_[pos_]))) {
        const std::size_t digit = static_cast<std::size_t>(text_[pos_++] - '0');
        if (value > (std::numeric_limits<std::size_t>::max() - digit) / 10) Bad("dimension too large");
        value = value * 10 + digit;
      }
      if (pos_ == start) Bad("expected a dimension");
      values.push_back(value);
      if (!Accept(',')) {
        Expect(')');
        break;
      }
    }
    return values;
  }

  const std::string& text_;
  const std::filesystem::path& path_;
  std::size_t pos_ = 0;
};

std::size_t ItemSize(const std::string& descr, const std::filesystem::path& path) {
  if (descr == "<f8") return 8;
  if (descr == "<f4") return 4;
  if (descr == "|u1" || descr == "<u1") return 1;
  const std::string order = !descr.empty() && descr[0] == '>' ? " (big-endian data is not supported)" : "";
  FailInvalid(path.string() + ": dtype '" + descr + "' is not supported" + order +
              "; expected '<f4', '<f8' or '|u1'");
}

}  // namespace

NpyArray ReadNpy(const std::filesystem::path& path) {
  // A pipe would block the read for ever (found 2026-12-05 with a FIFO as poses_bounds.npy).
  RequireRegularFile(path);
  std::ifstream in(path, std::ios::binary);
  if (!in) FailInvalid(path.string() + ": cannot open .npy file");
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string where = path.string();

  if (bytes.size() < kMagicSize + 2 || bytes.compare(0, kMagicSize, kMagic, kMagicSize) != 0) {
    FailInvalid(where + ": not a .npy file (the first bytes are not \\x93NUMPY)");
  }
  const int major = static_cast<unsigned char>(bytes[6]);
  const int minor = static_cast<unsigned char>(bytes[7]);
  if (major < 1 || major > 3) {
    FailInvalid(where + ": .npy format version " + std::to_string(major) + "." + std::to_string(minor) +
                " is not supported (expected 1, 2 or 3)");
  }
  const std::size_t length_bytes = major == 1 ? 2 : 4;
  const std::size_t preamble = kMagicSize + 2 + length_bytes;
  if (bytes.size() < preamble) FailInvalid(where + ": truncated .npy header");
  std::size_t header_length = 0;
  for (std::size_t i = 0; i < length_bytes; ++i) {
    header_length |= static_cast<std::size_t>(static_cast<unsigned char>(bytes[8 + i])) << (8 * i);
  }
  if (bytes.size() < preamble + header_length) {
    FailInvalid(where + ": truncated .npy header (declares " + std::to_string(header_length) +
                " bytes, file has " + std::to_string(bytes.size() - preamble) + ")");
  }

  NpyArray array;
  bool fortran_order = false;
  HeaderParser(bytes.substr(preamble, header_length), path).Parse(array.dtype, fortran_order, array.shape);
  if (fortran_order) FailInvalid(where + ": Fortran-order arrays are not supported (fortran_order is True)");
  const std::size_t item = ItemSize(array.dtype, path);

  std::size_t count = 1;
  for (std::size_t dim : array.shape) {
    if (dim != 0 && count > std::numeric_limits<std::size_t>::max() / item / dim) {
      FailInvalid(where + ": shape " + ShapeText(array.shape) + " is too large");
    }
    count *= dim;
  }
  const std::size_t have = bytes.size() - preamble - header_length;
  if (have != count * item) {
    FailInvalid(where + ": shape " + ShapeText(array.shape) + " of " + array.dtype + " needs " +
                std::to_string(count * item) + " data bytes, the file has " + std::to_string(have) +
                (have < count * item ? " (truncated)" : " (trailing bytes)"));
  }

  const char* data = bytes.data() + preamble + header_length;
  array.data.resize(count);
  for (std::size_t i = 0; i < count; ++i) {
    if (item == 8) {
      double value;
      std::memcpy(&value, data + 8 * i, 8);
      array.data[i] = value;
    } else if (item == 4) {
      float value;
      std::memcpy(&value, data + 4 * i, 4);
      array.data[i] = value;
    } else {
      array.data[i] = static_cast<unsigned char>(data[i]);
    }
  }
  return array;
}

namespace {

void WriteNpy(const std::filesystem::path& path, const char* descr, const void* data, std::size_t item_size,
              const std::vector<std::size_t>& shape) {
  std::string header =
      std::string("{'descr': '") + descr + "', 'fortran_order': False, 'shape': " + ShapeText(shape) + ", }";
  const std::size_t preamble = kMagicSize + 4;
  const std::size_t padded = (preamble + header.size() + 1 + 63) / 64 * 64;
  header.append(padded - preamble - header.size() - 1, ' ');
  header += '\n';

  std::size_t count = 1;
  for (std::size_t dim : shape) count *= dim;

  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(kMagic, kMagicSize);
  const char version_and_length[4] = {1, 0, static_cast<char>(header.size() & 0xff),
                                      static_cast<char>(header.size() >> 8)};
  out.write(version_and_length, 4);
  out << header;
  out.write(static_cast<const char*>(data), static_cast<std::streamsize>(count * item_size));
  out.close();
  if (!out) Fail(ErrorCode::kUnavailable, "cannot write " + path.string() + ": " + std::strerror(errno));
}

}  // namespace

void WriteNpyFloat32(const std::filesystem::path& path, const float* data,
                     const std::vector<std::size_t>& shape) {
  WriteNpy(path, "<f4", data, sizeof(float), shape);
}

void WriteNpyFloat64(const std::filesystem::path& path, const double* data,
                     const std::vector<std::size_t>& shape) {
  WriteNpy(path, "<f8", data, sizeof(double), shape);
}

}  // namespace endorecon
