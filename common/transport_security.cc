#include "common/transport_security.h"

#include <arpa/inet.h>
#include <fmt/chrono.h>
#include <grpcpp/create_channel.h>
#include <grpcpp/security/credentials.h>
#include <grpcpp/support/channel_arguments.h>
#include <grpcpp/support/client_interceptor.h>
#include <netinet/in.h>
#include <openssl/bio.h>
#include <openssl/err.h>
#include <openssl/evp.h>
#include <openssl/pem.h>
#include <openssl/x509.h>
#include <openssl/x509v3.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <charconv>
#include <ctime>
#include <memory>
#include <mutex>
#include <thread>
#include <utility>

#include "common/error.h"
#include "common/secret_file.h"

namespace endorecon {
namespace {

// "2021-01-01 00:00:00 UTC".
std::string AsnTimeText(const ASN1_TIME* time) {
  std::tm tm{};
  if (ASN1_TIME_to_tm(time, &tm) != 1) return "(an unreadable date)";
  char text[32];
  std::strftime(text, sizeof text, "%Y-%m-%d %H:%M:%S UTC", &tm);
  return text;
}

void RequirePair(const std::string& cert_file, const std::string& key_file) {
  if (cert_file.empty() != key_file.empty())
    FailInvalid("--tls-cert and --tls-key go together: give both or neither");
}

// Refuses a certificate and key that are not a pair, or not PEM at all, naming both files. gRPC
// found this only at the first connection ("Invalid private key", "Handshaker factory creation
// failed"), so a worker retried "empty address list" forever (found 2026-12-05) and the server
// failed to listen saying the port might be taken. OpenSSL, which endorecon links for SHA-256,
// reads and compares them. Also refused: a certificate not made for its side of TLS (`server`: a
// server's, else a client's), by its key usage and extended key usage: a server given a worker's
// certificate (clientAuth only) started, and every client failed "does not verify against --ca: is
// it signed by that CA, and valid now?", which it was (found 2026-12-07).
void CheckCertificateAndKey(const std::string& cert_pem, const std::string& key_pem,
                            const std::string& cert_file, const std::string& key_file, bool server) {
  const auto read = [](const std::string& pem) {
    return std::unique_ptr<BIO, decltype(&BIO_free)>(
        BIO_new_mem_buf(pem.data(), static_cast<int>(pem.size())), &BIO_free);
  };
  const auto cert_bio = read(cert_pem);
  // No password callback: OpenSSL's own would ask on the terminal for an encrypted key.
  pem_password_cb* const no_password = [](char*, int, int, void*) { return 0; };
  const std::unique_ptr<X509, decltype(&X509_free)> cert(
      PEM_read_bio_X509(cert_bio.get(), nullptr, no_password, nullptr), &X509_free);
  if (!cert) FailInvalid("--tls-cert " + cert_file + ": no PEM certificate in the file");
  const auto key_bio = read(key_pem);
  const std::unique_ptr<EVP_PKEY, decltype(&EVP_PKEY_free)> key(
      PEM_read_bio_PrivateKey(key_bio.get(), nullptr, no_password, nullptr), &EVP_PKEY_free);
  ERR_clear_error();  // what the failed reads left, so it is not reported by a later call
  if (!key) FailInvalid("--tls-key " + key_file + ": no PEM private key (unencrypted) in the file");
  if (X509_check_private_key(cert.get(), key.get()) != 1) {
    ERR_clear_error();
    FailInvalid("--tls-cert " + cert_file + " and --tls-key " + key_file +
                " are not a pair: the key belongs to another certificate");
  }
  // An expired certificate started and listened without a word; every peer then failed with a bare
  // "certificate verify failed" (found 2026-12-05).
  if (X509_cmp_current_time(X509_get0_notAfter(cert.get())) < 0) {
    FailInvalid("--tls-cert " + cert_file + " expired on " + AsnTimeText(X509_get0_notAfter(cert.get())) +
                ": renew it (docs/operations.md, \"Make the certificates\")");
  }
  if (X509_cmp_current_time(X509_get0_notBefore(cert.get())) > 0) {
    FailInvalid("--tls-cert " + cert_file + " is valid only from " +
                AsnTimeText(X509_get0_notBefore(cert.get())) + ": is this machine's clock right?");
  }
  if (X509_check_purpose(cert.get(), server ? X509_PURPOSE_SSL_SERVER : X509_PURPOSE_SSL_CLIENT, 0) != 1) {
    ERR_clear_error();
    FailInvalid("--tls-cert " + cert_file + " is not made for a TLS " + (server ? "server" : "client") +
                ": its extendedKeyUsage (or keyUsage) leaves out " + (server ? "serverAuth" : "clientAuth") +
                (server ? ", so clients refuse it; is it a worker's certificate? "
                        : ", so the server refuses it; is it the server's certificate? ") +
                "(docs/operations.md, \"Make the certificates\")");
  }
  constexpr long kWarnDays = 30;
  const auto soon = std::time(nullptr) + kWarnDays * 86400;
  if (X509_cmp_time(X509_get0_notAfter(cert.get()), const_cast<std::time_t*>(&soon)) < 0) {
    spdlog::warn("--tls-cert {} expires on {}, within {} days: renew it", cert_file,
                 AsnTimeText(X509_get0_notAfter(cert.get())), kWarnDays);
  }
}

// Warns once a process when the server says the token expires within kTokenExpiryWarning.
void WarnOfExpiry(std::string_view unix_ms_text) {
  static std::atomic<bool> warned{false};
  std::int64_t unix_ms = 0;
  if (std::from_chars(unix_ms_text.data(), unix_ms_text.data() + unix_ms_text.size(), unix_ms).ec !=
      std::errc{})
    return;
  const auto left = std::chrono::system_clock::time_point(std::chrono::milliseconds(unix_ms)) -
                    std::chrono::system_clock::now();
  if (left > kTokenExpiryWarning || warned.exchange(true)) return;
  // In the unit that says it: "in 0 hour(s)" was 33 s before a worker's token expired. Rounded to the
  // nearest: a token made for 3 days said "in 2 days" seconds later (found 2026-12-07).
  const long seconds = std::max<long>(0, std::chrono::duration_cast<std::chrono::seconds>(left).count());
  const long minutes = (seconds + 30) / 60;
  const std::string in = seconds < 120    ? fmt::format("{} s", seconds)
                         : minutes < 120  ? fmt::format("{} minutes", minutes)
                         : minutes < 2880 ? fmt::format("{} hours", (minutes + 30) / 60)
                                          : fmt::format("{} days", (minutes + 720) / 1440);
  spdlog::warn("the token in use expires at {:%Y-%m-%d %H:%M:%S} UTC, in {}: ask its issuer for a new one",
               fmt::gmtime(static_cast<std::time_t>(unix_ms / 1000)), in);
}

// Adds the bearer token to every call's initial metadata. An interceptor rather than call
// credentials, because gRPC sends call credentials only over TLS and a token store may guard a
// plaintext loopback server too.
class BearerTokenInterceptor final : public grpc::experimental::Interceptor {
 public:
  explicit BearerTokenInterceptor(std::string header) : header_(std::move(header)) {}
  void Intercept(grpc::experimental::InterceptorBatchMethods* methods) override {
    if (methods->QueryInterceptionHookPoint(
            grpc::experimental::InterceptionHookPoints::PRE_SEND_INITIAL_METADATA)) {
      methods->GetSendInitialMetadata()->emplace("authorization", header_);
    }
    if (methods->QueryInterceptionHookPoint(
            grpc::experimental::InterceptionHookPoints::POST_RECV_INITIAL_METADATA)) {
      if (const auto* received = methods->GetRecvInitialMetadata()) {
        if (const auto found = received->find(kTokenExpiresHeader); found != received->end())
          WarnOfExpiry(std::string_view(found->second.data(), found->second.size()));
      }
    }
    methods->Proceed();
  }

 private:
  const std::string header_;
};

// The header every call gets: a fixed token, or the token file's, read again when its modification
// time or size changes.
class BearerTokenFactory final : public grpc::experimental::ClientInterceptorFactoryInterface {
 public:
  explicit BearerTokenFactory(const ChannelSecurity& security) : file_(security.token_file) {
    if (file_.empty()) {
      header_ = "Bearer " + security.token;
    } else {
      stamp_ = StampOf();
      header_ = "Bearer " + ReadTokenFile(file_, "--token-file");
      checked_ = std::chrono::steady_clock::now();
    }
  }
  grpc::experimental::Interceptor* CreateClientInterceptor(grpc::experimental::ClientRpcInfo*) override {
    std::lock_guard lock(mutex_);
    if (!file_.empty() && std::chrono::steady_clock::now() - checked_ >= std::chrono::seconds(1)) Reread();
    return new BearerTokenInterceptor(header_);
  }

 private:
  using Stamp = std::pair<std::filesystem::file_time_type, std::uintmax_t>;
  Stamp StampOf() const {
    std::error_code error;
    const auto time = std::filesystem::last_write_time(file_, error);
    const auto size = std::filesystem::file_size(file_, error);
    return error ? Stamp{} : Stamp{time, size};
  }
  void Reread() {
    checked_ = std::chrono::steady_clock::now();
    const Stamp stamp = StampOf();
    if (stamp == stamp_) return;
    stamp_ = stamp;
    try {
      header_ = "Bearer " + ReadTokenFile(file_, "--token-file");
      spdlog::info("--token-file {} changed: calls carry its new token", file_.string());
    } catch (const Error& e) {
      spdlog::warn("--token-file {} changed but holds no usable token ({}); calls keep the last one",
                   file_.string(), e.what());
    }
  }

  const std::filesystem::path file_;
  std::mutex mutex_;
  std::string header_;
  Stamp stamp_;
  std::chrono::steady_clock::time_point checked_;
};

}  // namespace

std::shared_ptr<grpc::Channel> OpenChannel(const std::string& address, const ChannelSecurity& security) {
  RequirePair(security.cert_file, security.key_file);
  if (!security.cert_file.empty() && security.ca_file.empty())
    FailInvalid("--tls-cert needs --ca: a client certificate is presented only over TLS");
  // A token in plaintext is anyone's on the path: only to this machine (a server refuses to listen
  // in plaintext beyond loopback, so such an address is a proxy or someone else; the CLI and the
  // worker sent it there until 2026-12-06).
  const bool token = !security.token.empty() || !security.token_file.empty();
  if (token && security.ca_file.empty() && !security.insecure && !IsLoopbackAddress(address)) {
    FailInvalid(
        "a token is sent only over TLS beyond this machine: give --ca (the CA that signed the "
        "server's certificate) to reach " +
        address + ", reach the server on loopback, or on an isolated test network --insecure");
  }
  std::shared_ptr<grpc::ChannelCredentials> credentials = grpc::InsecureChannelCredentials();
  if (!security.ca_file.empty()) {
    grpc::SslCredentialsOptions tls;
    tls.pem_root_certs = ReadPublicFile(security.ca_file, "--ca");
    if (!security.cert_file.empty()) {
      tls.pem_cert_chain = ReadPublicFile(security.cert_file, "--tls-cert");
      tls.pem_private_key = ReadSecretFile(security.key_file, "--tls-key");
      CheckCertificateAndKey(tls.pem_cert_chain, tls.pem_private_key, security.cert_file, security.key_file,
                             /*server=*/false);
    }
    credentials = grpc::SslCredentials(tls);
  }
  grpc::ChannelArguments args;
  args.SetMaxReceiveMessageSize(kMaxMessageBytes);
  args.SetMaxSendMessageSize(kMaxMessageBytes);
  // Reconnect within seconds after a server restart (gRPC's default backoff grows to 120 s), so
  // workers come back well inside their lease TTL. GRPC_ARG_MIN_RECONNECT_BACKOFF_MS stays at its
  // default: despite its name gRPC takes it as the time one connection attempt may take to open
  // (20 s), and a short one fails every call over a link slower than it (SlowLinkTest).
  args.SetInt(GRPC_ARG_MAX_RECONNECT_BACKOFF_MS, 2000);
  args.SetInt(GRPC_ARG_INITIAL_RECONNECT_BACKOFF_MS, 200);
  if (security.token.empty() && security.token_file.empty())
    return grpc::CreateCustomChannel(address, credentials, args);
  std::vector<std::unique_ptr<grpc::experimental::ClientInterceptorFactoryInterface>> interceptors;
  interceptors.push_back(std::make_unique<BearerTokenFactory>(security));
  return grpc::experimental::CreateCustomChannelWithInterceptors(address, credentials, args,
                                                                 std::move(interceptors));
}

std::shared_ptr<grpc::ServerCredentials> ServerCredentials(const ServerSecurity& security) {
  RequirePair(security.cert_file, security.key_file);
  if (!security.tls()) {
    if (!security.client_ca_file.empty()) FailInvalid("--tls-client-ca needs --tls-cert and --tls-key");
    return grpc::InsecureServerCredentials();
  }
  grpc::SslServerCredentialsOptions tls(security.client_ca_file.empty()
                                            ? GRPC_SSL_DONT_REQUEST_CLIENT_CERTIFICATE
                                            : GRPC_SSL_REQUEST_CLIENT_CERTIFICATE_AND_VERIFY);
  tls.pem_key_cert_pairs.push_back(
      {ReadSecretFile(security.key_file, "--tls-key"), ReadPublicFile(security.cert_file, "--tls-cert")});
  CheckCertificateAndKey(tls.pem_key_cert_pairs[0].cert_chain, tls.pem_key_cert_pairs[0].private_key,
                         security.cert_file, security.key_file, /*server=*/true);
  if (!security.client_ca_file.empty())
    tls.pem_root_certs = ReadPublicFile(security.client_ca_file, "--tls-client-ca");
  return grpc::SslServerCredentials(tls);
}

std::string CleanToken(std::string_view text, const std::string& source) {
  if (text.starts_with("\xEF\xBB\xBF")) text.remove_prefix(3);
  const auto begin = text.find_first_not_of(" \t\r\n");
  const auto end = text.find_last_not_of(" \t\r\n");
  const std::string_view token = begin == std::string::npos ? "" : text.substr(begin, end - begin + 1);
  // A malformed token is refused as the server refuses one (exit 10, which a script maps to "get a new
  // token"); a bad byte in it was exit 2 while "garbage" was 10 (found 2026-12-06).
  if (token.empty() || token.find_first_of(" \t\r\n") != std::string::npos)
    Fail(ErrorCode::kUnauthenticated, source + ": expected one token (one word)");
  for (std::size_t i = 0; i < token.size(); ++i) {
    const auto byte = static_cast<unsigned char>(token[i]);
    if (byte < 0x21 || byte > 0x7e) {
      Fail(ErrorCode::kUnauthenticated,
           source + ": the token holds byte 0x" + fmt::format("{:02x}", byte) + " at position " +
               std::to_string(i + 1) +
               "; a token is printable ASCII, as endorecon-server token create prints it");
    }
  }
  return std::string(token);
}

std::string ReadTokenFile(const std::filesystem::path& path, const std::string& flag) {
  return CleanToken(ReadSecretFile(path, flag), flag + " " + path.string());
}

std::string WithoutTokens(std::string text) {
  constexpr std::string_view kPrefix = "endorecon.";
  constexpr std::string_view kHex = "0123456789abcdef";
  for (auto at = text.find(kPrefix); at != std::string::npos; at = text.find(kPrefix, at + 1)) {
    const auto dot = text.find_first_not_of(kHex, at + kPrefix.size());
    if (dot == std::string::npos || text[dot] != '.' || dot == at + kPrefix.size()) continue;
    auto end = text.find_first_not_of(kHex, dot + 1);
    if (end == std::string::npos) end = text.size();
    if (end - dot - 1 >= 16) text.replace(dot + 1, end - dot - 1, "\u2026");  // "…"
  }
  return text;
}

bool IsLoopbackAddress(const std::string& address) {
  std::string host = address;
  if (host.rfind("unix:", 0) == 0) return true;
  if (!host.empty() && host.front() == '[') {
    host = host.substr(1, host.find(']') - 1);
  } else if (const auto colon = host.rfind(':'); colon != std::string::npos) {
    host = host.substr(0, colon);
  }
  // An address, not a name that looks like one: "127.evil.example" resolves wherever its owner likes
  // (found 2026-12-06).
  if (host == "localhost") return true;
  in_addr v4{};
  if (::inet_pton(AF_INET, host.c_str(), &v4) == 1) return (ntohl(v4.s_addr) >> 24) == 127;
  in6_addr v6{};
  return ::inet_pton(AF_INET6, host.c_str(), &v6) == 1 && IN6_IS_ADDR_LOOPBACK(&v6);
}

void PauseBeforeRetry(grpc::Channel& channel, std::chrono::milliseconds pause) {
  if (channel.GetState(false) == GRPC_CHANNEL_READY) {
    std::this_thread::sleep_for(pause);
  } else {
    channel.WaitForConnected(std::chrono::system_clock::now() + pause);
  }
}

std::string TlsFailureHint(std::string_view message, const ChannelSecurity& security) {
  if (security.ca_file.empty()) return "";
  std::string lower(message);
  std::transform(lower.begin(), lower.end(), lower.begin(), [](unsigned char c) { return std::tolower(c); });
  const auto has = [&](std::string_view word) { return lower.find(word) != std::string::npos; };
  if (has("certificate verify failed") || has("certificate_verify_failed")) {
    return "the server's certificate does not verify against --ca " + security.ca_file +
           ": is it signed by that CA, and valid now?";
  }
  // gRPC's "Peer name 127.0.0.2 is not in peer certificate": the certificate verified, for other names
  // (said with no hint until 2026-12-07).
  if (has("is not in peer certificate")) {
    return "the server's certificate does not name the address dialled: dial one of the names it was "
           "made for (its subjectAltName), or make it anew naming this one (docs/operations.md, \"Make the "
           "certificates\")";
  }
  if (has("wrong version number") || has("wrong_version_number")) {
    return "the address does not answer in TLS: a server without --tls-cert (then drop --ca), or a port "
           "that is not its --listen, such as its health port";
  }
  return "";
}

std::unique_ptr<grpc::ClientContext> CallContext(std::chrono::milliseconds timeout) {
  auto context = std::make_unique<grpc::ClientContext>();
  context->set_deadline(std::chrono::system_clock::now() + timeout);
  return context;
}

}  // namespace endorecon
