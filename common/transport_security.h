// The one place where transport security and caller identity are decided, for every binary.
//
// Today the service speaks plaintext and binds to loopback unless told otherwise. The next step
// (TLS and per-call tokens) lands here without touching callers: OpenChannel() composes
// grpc::SslCredentials with a token (grpc::AccessTokenCredentials or a MetadataCredentialsPlugin),
// ServerCredentials() returns grpc::SslServerCredentials, and the server checks the token in one
// grpc::experimental::ServerInterceptor (UNAUTHENTICATED / PERMISSION_DENIED).
#pragma once

#include <grpcpp/channel.h>
#include <grpcpp/client_context.h>
#include <grpcpp/security/server_credentials.h>

#include <chrono>
#include <memory>
#include <string>

namespace endorecon {

// Largest gRPC message either side accepts: a 4 MiB chunk plus its envelope.
inline constexpr int kMaxMessageBytes = 4 * 1024 * 1024 + 64 * 1024;
// Upload and download chunks carry at most this many bytes (strictly below 4 MiB).
inline constexpr int kChunkBytes = 4 * 1024 * 1024 - 4096;

// A channel to `address` ("host:port") with the service's credentials and message limits.
std::shared_ptr<grpc::Channel> OpenChannel(const std::string& address);

std::shared_ptr<grpc::ServerCredentials> ServerCredentials();

// True when `address` ("host:port", "[v6]:port") names a loopback interface only.
bool IsLoopbackAddress(const std::string& address);

// A context whose call must finish within `timeout` (every client call has a deadline); the
// place where per-call tokens will be attached.
std::unique_ptr<grpc::ClientContext> CallContext(std::chrono::milliseconds timeout);

}  // namespace endorecon
