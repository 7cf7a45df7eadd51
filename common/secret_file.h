// Files that hold secrets (TLS private keys, bearer tokens) and the public files beside them
// (certificates). A secret file that other users may read is refused before it is used, as ssh
// refuses a private key: group read stays allowed, so a key owned by root and the service's group
// (mode 0640, or Kubernetes' secret volumes with an fsGroup) works.
#pragma once

#include <filesystem>
#include <string>

namespace endorecon {

// The contents of `path`, named by `flag` ("--tls-key") in every error. Throws
// Error(kInvalidArgument) when the file is readable, writable or executable by others (naming its
// mode and the chmod that fixes it), kNotFound when it cannot be read or is empty.
std::string ReadSecretFile(const std::filesystem::path& path, const std::string& flag);

// The contents of a non-secret file (a certificate, a CA bundle: PEM). Throws Error(kNotFound) naming
// `flag` when it cannot be read, kInvalidArgument when it is empty, no regular file or holds no PEM
// certificate.
std::string ReadPublicFile(const std::filesystem::path& path, const std::string& flag);

}  // namespace endorecon
