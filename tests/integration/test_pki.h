// Certificates for the TLS tests, made at test time with the openssl command line (no key is ever
// committed): a CA, a server certificate for 127.0.0.1 and localhost, a worker's client
// certificate, an expired server certificate, and a second CA (untrusted by everyone) with a server
// certificate of its own. EC P-256 keys, so the whole set takes well under a second.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace endorecon::testing {

struct TestPki {
  // Writes everything into `dir` (keys with mode 0600). Throws std::runtime_error naming the
  // openssl command that failed.
  explicit TestPki(const std::filesystem::path& dir);

  std::filesystem::path ca_cert;
  std::filesystem::path server_cert, server_key;
  std::filesystem::path worker_cert, worker_key;    // client certificate signed by the CA
  std::filesystem::path expired_cert, expired_key;  // signed by the CA, notAfter in the past
  std::filesystem::path rogue_ca_cert;              // a CA nobody trusts
  std::filesystem::path rogue_cert, rogue_key;      // server and client certificate signed by it
};

// Server flags for TLS with `pki`'s server certificate, client certificates required on the worker API.
std::vector<std::string> ServerTlsFlags(const TestPki& pki);
// Worker flags: verify the server against the CA, present the worker certificate, send the token in
// `token_file`.
std::vector<std::string> WorkerTlsFlags(const TestPki& pki, const std::string& token_file);

}  // namespace endorecon::testing
