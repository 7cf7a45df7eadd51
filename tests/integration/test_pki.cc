#include "tests/integration/test_pki.h"

#include <cstdlib>
#include <stdexcept>
#include <string>

#include "tests/unit/temp_dir.h"

namespace endorecon::testing {
namespace fs = std::filesystem;
namespace {

void Run(const std::string& command) {
  if (std::system((command + " >/dev/null 2>&1").c_str()) != 0)
    throw std::runtime_error("openssl failed: " + command);
}

// Quoted for the shell. Appended piece by piece: GCC 12 flags "'" + string + "'" with a false -Wrestrict.
std::string Q(const fs::path& path) {
  std::string quoted = "'";
  quoted += path.string();
  quoted += '\'';
  return quoted;
}

void SelfSignedCa(const fs::path& cert, const fs::path& key, const std::string& name) {
  Run("openssl req -x509 -newkey ec -pkeyopt ec_paramgen_curve:P-256 -nodes -keyout " + Q(key) + " -out " +
      Q(cert) + " -days 2 -subj /CN=" + name +
      " -addext basicConstraints=critical,CA:TRUE -addext keyUsage=critical,keyCertSign");
}

// `days` < 0 makes a certificate whose notAfter lies in the past (expired from the start).
void Signed(const fs::path& dir, const fs::path& ca_cert, const fs::path& ca_key, const fs::path& cert,
            const fs::path& key, const std::string& name, const std::string& extensions, int days) {
  const auto csr = dir / (name + ".csr");
  const auto ext = dir / (name + ".ext");
  WriteBytes(ext, extensions + "\n");
  Run("openssl req -newkey ec -pkeyopt ec_paramgen_curve:P-256 -nodes -keyout " + Q(key) + " -out " + Q(csr) +
      " -subj /CN=" + name);
  Run("openssl x509 -req -in " + Q(csr) + " -CA " + Q(ca_cert) + " -CAkey " + Q(ca_key) +
      " -CAcreateserial -days " + std::to_string(days) + " -extfile " + Q(ext) + " -out " + Q(cert));
  fs::permissions(key, fs::perms::owner_read | fs::perms::owner_write);
}

}  // namespace

TestPki::TestPki(const fs::path& dir) {
  const std::string server_ext = "subjectAltName=IP:127.0.0.1,DNS:localhost\nextendedKeyUsage=serverAuth";
  const std::string client_ext = "extendedKeyUsage=clientAuth";
  const auto ca_key = dir / "ca.key";
  ca_cert = dir / "ca.crt";
  SelfSignedCa(ca_cert, ca_key, "endorecon-test-ca");
  server_cert = dir / "server.crt";
  server_key = dir / "server.key";
  Signed(dir, ca_cert, ca_key, server_cert, server_key, "localhost", server_ext, 2);
  worker_cert = dir / "worker.crt";
  worker_key = dir / "worker.key";
  Signed(dir, ca_cert, ca_key, worker_cert, worker_key, "worker-1", client_ext, 2);
  expired_cert = dir / "expired.crt";
  expired_key = dir / "expired.key";
  Signed(dir, ca_cert, ca_key, expired_cert, expired_key, "expired", server_ext, -1);
  const auto rogue_ca_key = dir / "rogue-ca.key";
  rogue_ca_cert = dir / "rogue-ca.crt";
  SelfSignedCa(rogue_ca_cert, rogue_ca_key, "rogue-ca");
  rogue_cert = dir / "rogue.crt";
  rogue_key = dir / "rogue.key";
  Signed(dir, rogue_ca_cert, rogue_ca_key, rogue_cert, rogue_key, "rogue",
         "subjectAltName=IP:127.0.0.1,DNS:localhost\nextendedKeyUsage=serverAuth,clientAuth", 2);
}

std::vector<std::string> ServerTlsFlags(const TestPki& pki) {
  return {"--tls-cert",      pki.server_cert.string(), "--tls-key", pki.server_key.string(),
          "--tls-client-ca", pki.ca_cert.string()};
}

std::vector<std::string> WorkerTlsFlags(const TestPki& pki, const std::string& token_file) {
  return {"--ca",      pki.ca_cert.string(),    "--tls-cert",   pki.worker_cert.string(),
          "--tls-key", pki.worker_key.string(), "--token-file", token_file};
}

}  // namespace endorecon::testing
