#include "client/exit_codes.h"

namespace endorecon::client {

int ExitCodeFor(ErrorCode code) {
  switch (code) {
    case ErrorCode::kInvalidArgument:
      return kExitInvalid;
    case ErrorCode::kNotFound:
      return kExitNotFound;
    case ErrorCode::kFailedPrecondition:
      return kExitPrecondition;
    case ErrorCode::kResourceExhausted:
      return kExitResourceExhausted;
    case ErrorCode::kUnavailable:
      return kExitUnavailable;
    case ErrorCode::kDataLoss:
      return kExitDataLoss;
    case ErrorCode::kCancelled:
      return kExitJobCancelled;
    case ErrorCode::kInternal:
      return kExitInternal;
    case ErrorCode::kUnauthenticated:
      return kExitUnauthenticated;
    case ErrorCode::kPermissionDenied:
      return kExitPermissionDenied;
  }
  return kExitInternal;
}

int ExitCodeFor(v1::JobState state) {
  if (state == v1::FAILED) return kExitJobFailed;
  if (state == v1::CANCELLED) return kExitJobCancelled;
  return kExitOk;
}

}  // namespace endorecon::client
