// The one place where transport security is decided, for every binary: TLS (and client
// certificates) on channels and listening ports, and the bearer token every client call carries.
// Which caller may do what is the server's CallGuard (server/call_guard.h).
#pragma once

#include <grpcpp/channel.h>
#include <grpcpp/client_context.h>
#include <grpcpp/security/server_credentials.h>

#include <chrono>
#include <filesystem>
#include <memory>
#include <string>
#include <string_view>

namespace endorecon {

// The initial metadata in which the server tells a caller whose token expires when (Unix ms).
inline constexpr const char* kTokenExpiresHeader = "endorecon-token-expires";
// A channel warns (once) when its token expires within this long.
inline constexpr std::chrono::hours kTokenExpiryWarning{24 * 7};

// Largest gRPC message either side accepts: a 4 MiB chunk plus its envelope.
inline constexpr int kMaxMessageBytes = 4 * 1024 * 1024 + 64 * 1024;
// Upload and download chunks carry at most this many bytes (strictly below 4 MiB).
inline constexpr int kChunkBytes = 4 * 1024 * 1024 - 4096;

// How a client or worker reaches the server. All empty: plaintext without a token (loopback).
struct ChannelSecurity {
  std::string ca_file;    // TLS: verify the server's certificate against this CA bundle (--ca)
  std::string cert_file;  // mTLS: present this certificate chain (--tls-cert), with key_file
  std::string key_file;   // its private key (--tls-key); refused when others may read it
  std::string token;      // sent as "authorization: Bearer <token>" with every call
  // Instead of `token`: the token file (--token-file), read when the channel opens and read again
  // when it changes (checked at most once a second), so a long-running worker takes a rotated token
  // without a restart. A changed file that holds no valid token is warned of and the last token kept.
  std::string token_file;
  // Send the token without TLS beyond loopback too (--insecure: isolated test networks, as the
  // server's --insecure); refused otherwise.
  bool insecure = false;
};

// A channel to `address` ("host:port") with `security` and the service's message limits. Throws
// Error(kInvalidArgument) for a certificate without its key (or the reverse) or a key file others
// may read, kNotFound for a file that cannot be read.
std::shared_ptr<grpc::Channel> OpenChannel(const std::string& address, const ChannelSecurity& security = {});

// The server's side. All empty: plaintext.
struct ServerSecurity {
  std::string cert_file;       // --tls-cert: the server's certificate chain
  std::string key_file;        // --tls-key: its private key
  std::string client_ca_file;  // --tls-client-ca: ask callers for a certificate, verify it against this CA
  bool tls() const { return !cert_file.empty(); }
};

// Credentials for a listening port. With a client CA, a caller may present a certificate (then it
// must verify, or the handshake fails) but need not: the worker API demands one (CallGuard).
// Throws as OpenChannel.
std::shared_ptr<grpc::ServerCredentials> ServerCredentials(const ServerSecurity& security = {});

// The token in `text` (from `source`, named in errors): surrounding whitespace and a leading UTF-8
// byte-order mark removed (an editor's), then one word of printable ASCII. A control or other byte
// inside is refused with kUnauthenticated (a malformed token, exit 10 as the server's refusal of one)
// naming its position: gRPC aborted the process on one in a header value (a token set with a trailing
// newline crashed the CLI; found 2026-12-05).
std::string CleanToken(std::string_view text, const std::string& source);

// `text` with the secret part of every token in it ("endorecon.ID.SECRET") withheld: "endorecon.ID.…".
// For messages that repeat what a user typed.
std::string WithoutTokens(std::string text);
// The token in `path`, checked as a secret file and by CleanToken. Throws as ReadSecretFile and
// CleanToken.
std::string ReadTokenFile(const std::filesystem::path& path, const std::string& flag);

// True when `address` ("host:port", "[v6]:port") names a loopback interface only.
bool IsLoopbackAddress(const std::string& address);

// The wait before a failed call over `channel` is tried again: `pause` while the connection is up
// (the server answered; a refusal or a broken stream), else until it is back, `pause` at most.
// Calls that fail fast while the server is away leave nothing watching the connection attempts but
// gRPC's backup poller, every 5 s; waiting on the channel watches them, so a restarted server is
// called again within moments of its return.
void PauseBeforeRetry(grpc::Channel& channel, std::chrono::milliseconds pause);

// What a caller (the CLI, a worker) can do about a failed connection whose gRPC `message` tells a TLS
// failure, or "" when it tells none: a server certificate the caller's --ca does
// not verify, and TLS spoken to a port that answers without it (a plaintext server, or its health
// port). gRPC's words alone sent users to the other side's settings (found 2026-12-05).
std::string TlsFailureHint(std::string_view message, const ChannelSecurity& security);

// A context whose call must finish within `timeout` (every client call has a deadline).
std::unique_ptr<grpc::ClientContext> CallContext(std::chrono::milliseconds timeout);

}  // namespace endorecon
