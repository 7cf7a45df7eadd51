// The exit codes of `endorecon`, the same for every subcommand (also printed by --help).
#pragma once

#include "common/error.h"
#include "endorecon/v1/job.pb.h"

namespace endorecon::client {

enum ExitCode : int {
  kExitOk = 0,
  kExitInternal = 1,           // an unexpected error
  kExitInvalid = 2,            // bad usage or input, rejected locally or by the server
  kExitNotFound = 3,           // no such job, file or folder
  kExitUnavailable = 4,        // the server cannot be reached or the call timed out
  kExitJobFailed = 5,          // the job ended FAILED
  kExitJobCancelled = 6,       // the job ended CANCELLED
  kExitPrecondition = 7,       // not possible in the job's state (fetch before it succeeded, ...)
  kExitResourceExhausted = 8,  // a server limit was hit (upload size, disk)
  kExitDataLoss = 9,           // a checksum did not match
  kExitUnauthenticated = 10,   // no token, or one the server does not accept (unknown, revoked, malformed)
  kExitPermissionDenied = 11,  // the token's role may not do this
};

inline constexpr const char* kExitCodeHelp =
    "Exit codes: 0 ok, 1 internal error, 2 invalid usage or input, 3 not found, 4 server unavailable or "
    "timed out, 5 job failed, 6 job cancelled, 7 not possible in the job's state, 8 server limit exceeded, "
    "9 checksum mismatch, 10 not authenticated, 11 not permitted. The server address comes from --server, "
    "else "
    "$ENDORECON_SERVER, else 127.0.0.1:50051.";

int ExitCodeFor(ErrorCode code);
// 0 for SUCCEEDED, 5 for FAILED, 6 for CANCELLED, 0 otherwise (still running).
int ExitCodeFor(v1::JobState state);

}  // namespace endorecon::client
