#include "common/sealed_file.h"

#include <algorithm>
#include <array>
#include <streambuf>
#include <string>

#include "common/error.h"
#include "common/file_read.h"
#include "common/file_write.h"
#include "common/sha256.h"

namespace endorecon {
namespace {

constexpr std::size_t kDigestChars = 64;

// Passes every byte on to `target` and into the digest.
class HashingBuffer : public std::streambuf {
 public:
  HashingBuffer(std::streambuf* target, Sha256& digest) : target_(target), digest_(digest) {}

 protected:
  int_type overflow(int_type c) override {
    if (traits_type::eq_int_type(c, traits_type::eof())) return traits_type::not_eof(c);
    const char byte = traits_type::to_char_type(c);
    digest_.Update(&byte, 1);
    return target_->sputc(byte);
  }
  std::streamsize xsputn(const char* s, std::streamsize n) override {
    digest_.Update(s, static_cast<std::size_t>(n));
    return target_->sputn(s, n);
  }

 private:
  std::streambuf* target_;
  Sha256& digest_;
};

}  // namespace

void WriteSealedFile(const std::filesystem::path& path, const char (&magic)[8],
                     const std::function<void(std::ostream&)>& body, std::string_view what) {
  WriteFileWith(
      path,
      [&](std::ostream& out) {
        Sha256 digest;
        HashingBuffer buffer(out.rdbuf(), digest);
        std::ostream hashed(&buffer);
        hashed.write(magic, 8);
        body(hashed);
        hashed.flush();
        if (!hashed) out.setstate(std::ios::badbit);
        out << digest.HexDigest();
      },
      what);
}

std::ifstream OpenSealedFile(const std::filesystem::path& path, const char (&magic)[8],
                             std::string_view what) {
  const std::string name(what);
  RequireRegularFile(path);
  std::ifstream in(path, std::ios::binary);
  if (!in) Fail(ErrorCode::kNotFound, "cannot read " + name + " " + path.string());
  char found[8] = {};
  in.read(found, 8);
  if (!in || !std::equal(found, found + 7, magic)) {
    // Another of endorecon's sealed files (a checkpoint where a model goes): say which it is.
    const bool ours = in && std::equal(found, found + 4, magic) &&
                      std::all_of(found + 4, found + 8, [](char c) { return c >= '0' && c <= 'Z'; });
    FailInvalid(
        path.string() + " is not an endorecon " + name + " file" +
        (ours ? " but another of endorecon's files (its header says " + std::string(found, 8) + ")" : ""));
  }
  if (found[7] != magic[7]) {
    FailInvalid(path.string() + ": an endorecon " + name + " of format " + std::string(1, found[7]) +
                "; this build reads format " + std::string(1, magic[7]));
  }
  std::error_code ec;
  const auto size = std::filesystem::file_size(path, ec);
  if (ec || size < 8 + kDigestChars)
    Fail(ErrorCode::kDataLoss, path.string() + ": truncated " + name + " file");
  Sha256 digest;
  digest.Update(found, 8);
  std::array<char, 1 << 16> chunk;
  for (std::uintmax_t left = size - 8 - kDigestChars; left > 0;) {
    const auto n = static_cast<std::streamsize>(std::min<std::uintmax_t>(left, chunk.size()));
    in.read(chunk.data(), n);
    if (!in) Fail(ErrorCode::kDataLoss, path.string() + ": truncated " + name + " file");
    digest.Update(chunk.data(), static_cast<std::size_t>(n));
    left -= static_cast<std::uintmax_t>(n);
  }
  std::string stored(kDigestChars, '\0');
  in.read(stored.data(), kDigestChars);
  if (!in || stored != digest.HexDigest()) {
    Fail(ErrorCode::kDataLoss,
         path.string() + ": the " + name +
             " file is corrupt (its SHA-256 does not match: changed, truncated or extended)");
  }
  in.clear();
  in.seekg(8);
  return in;
}

}  // namespace endorecon
