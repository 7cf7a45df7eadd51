// A folder that holds patient data (the server's data folder, a worker's scratch folder) is its
// owner's alone: what the process creates from then on is owner-only (umask 077), and the folder
// itself loses any access for its group and others, so the files already in it cannot be reached
// either. The job store held patients' names in a file every local user could read.
#pragma once

#include <filesystem>

namespace endorecon {

// Creates `dir` (and its parents) if missing, sets the process's umask to 077 and removes the
// group's and others' permissions from `dir`. Returns whether `dir` had any to remove.
// Throws Error(kInvalidArgument) naming `dir` when it cannot be created or changed.
bool MakePrivateFolder(const std::filesystem::path& dir);

}  // namespace endorecon
