// A folder that holds patient data (the server's data folder, a worker's scratch folder) is its
// owner's alone: what the process creates from then on is owner-only (umask 077), so a folder it
// creates is too. The job store held patients' names in a file every local user could read.
#pragma once

#include <filesystem>

namespace endorecon {

// Sets the process's umask to 077 and creates `dir` (and its parents) if missing. Returns whether
// `dir` is open to its group or others: an existing folder is left as it is (it may be a shared
// one, such as /tmp, named by mistake), for the caller to warn of.
// Throws Error(kInvalidArgument) naming `dir` when it cannot be created or read.
bool MakePrivateFolder(const std::filesystem::path& dir);

}  // namespace endorecon
