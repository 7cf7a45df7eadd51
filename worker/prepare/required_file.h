// A file a recording's preparation needs (a calibration, a pose file), checked before it is read.
#pragma once

#include <filesystem>
#include <string>

namespace endorecon::prepare {

// Throws Error naming `path` as `what` ("calibration file"): kNotFound when nothing is there,
// kInvalidArgument when it is a folder or anything else that is not a regular file.
void RequireRegularFile(const std::filesystem::path& path, const std::string& what);

}  // namespace endorecon::prepare
