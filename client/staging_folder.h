// The CLI's temporary folders (a raw recording staged under canonical names, a clip cut to the
// frames --frames picks): $TMPDIR/endorecon-KIND-PID-N, its owner's alone (it holds links to patient
// data). A folder a CLI killed mid-way left (Ctrl-C, SIGTERM, a crash: no destructor runs) is removed
// by the next one that makes a folder of that kind.
#pragma once

#include <filesystem>
#include <string>

namespace endorecon::client {

// Makes a new folder of `kind` ("recording", "clip"), first removing those of processes that are
// gone. Throws Error(kInvalidArgument) naming $TMPDIR when no temporary folder can be made there.
std::filesystem::path MakeStagingFolder(const std::string& kind);

}  // namespace endorecon::client
