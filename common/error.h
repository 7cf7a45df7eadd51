// Errors travel as endorecon::Error: a code (mapped one-to-one onto gRPC status codes at the
// service boundary) and a message that says what is wrong and where (file, field, frame).
#pragma once

#include <stdexcept>
#include <string>

namespace endorecon {

enum class ErrorCode {
  kInvalidArgument,     // the input is malformed: a bad file, a bad flag, a bad field
  kNotFound,            // a named thing does not exist
  kFailedPrecondition,  // the system is not in a state to do this
  kResourceExhausted,   // a size or count limit was exceeded
  kUnavailable,         // a peer or resource could not be reached; retrying may help
  kDataLoss,            // stored data is corrupt (checksum mismatch, truncated file)
  kInternal,            // a broken invariant: a bug, or numerics that went non-finite
  kCancelled,           // the work was cancelled on request
  kUnauthenticated,     // the caller's identity is missing or not accepted (token, certificate)
  kPermissionDenied,    // the caller is known but its role may not do this
};

const char* ErrorCodeName(ErrorCode code);

class Error : public std::runtime_error {
 public:
  Error(ErrorCode code, const std::string& message) : std::runtime_error(message), code_(code) {}
  ErrorCode code() const { return code_; }

 private:
  ErrorCode code_;
};

[[noreturn]] inline void Fail(ErrorCode code, const std::string& message) { throw Error(code, message); }
[[noreturn]] inline void FailInvalid(const std::string& message) {
  throw Error(ErrorCode::kInvalidArgument, message);
}

}  // namespace endorecon
