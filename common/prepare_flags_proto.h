// PrepareFlags on the wire (v1::PrepareOptions) and back: the CLI sends them with a raw
// recording, the server checks them, the worker prepares by them.
#pragma once

#include "common/prepare_flags.h"
#include "endorecon/v1/files.pb.h"
#include "endorecon/v1/job.pb.h"

namespace endorecon {

v1::PrepareOptions PrepareFlagsToProto(const PrepareFlags& flags);
PrepareFlags PrepareFlagsFromProto(const v1::PrepareOptions& options);

// Throws Error(kInvalidArgument) naming the option when the flags are inconsistent
// (CheckPrepareFlags) or a path they name is neither a file of `recording` nor a folder holding
// some of its files.
void CheckPrepareOptions(const v1::PrepareOptions& options, const v1::Manifest& recording);

}  // namespace endorecon
