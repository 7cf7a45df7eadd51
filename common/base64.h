// Base64 (RFC 4648, standard alphabet, padded, no line breaks), as data: URIs and JSON carry bytes.
#pragma once

#include <string>
#include <string_view>

namespace endorecon {

// The encoding of `bytes` (any content, including NUL); "" for no bytes.
std::string Base64(std::string_view bytes);

}  // namespace endorecon
