// The service boundary: endorecon::Error codes map one-to-one onto gRPC status codes, both ways.
#pragma once

#include <grpcpp/support/status.h>

#include <exception>
#include <string_view>

#include "common/error.h"

namespace endorecon {

grpc::StatusCode ToGrpcCode(ErrorCode code);
// DEADLINE_EXCEEDED and UNAVAILABLE both become kUnavailable (retrying may help).
ErrorCode FromGrpcCode(grpc::StatusCode code);

// Runs a handler body: an endorecon::Error becomes its status with the message, any other
// exception INTERNAL. Every RPC handler goes through this, so no exception escapes into gRPC.
template <typename Body>
grpc::Status GuardStatus(Body&& body) {
  try {
    return body();
  } catch (const Error& e) {
    return grpc::Status(ToGrpcCode(e.code()), e.what());
  } catch (const std::exception& e) {
    return grpc::Status(grpc::StatusCode::INTERNAL, e.what());
  }
}

// Throws Error("<what>: <message>") with the mapped code unless `status` is OK.
void ThrowIfFailed(const grpc::Status& status, std::string_view what);

}  // namespace endorecon
