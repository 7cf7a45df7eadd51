// Opening a file to read it, with the system's reason when it cannot be opened: "cannot open the file"
// alone left a user guessing at an unreadable image (found 2026-12-06).
#pragma once

#include <filesystem>
#include <fstream>
#include <string>

namespace endorecon {

// `path` opened for binary reading. Throws Error(kInvalidArgument): "PATH: cannot open the file
// (Permission denied)", or RequireRegularFile's.
std::ifstream OpenToRead(const std::filesystem::path& path);

// Throws Error(kInvalidArgument) when `path` (its links followed) exists and is no regular file:
// "PATH: a named pipe (FIFO), not a WHAT" (a folder, a socket, a device alike). Opening a FIFO to
// read it waits for a writer: a server given one for --quotas or --tls-cert hung at start, deaf to
// SIGTERM, and so did the worker's and the CLI's commands given one for an input (found 2026-12-06).
// A path that does not exist is left to the open, which names it.
void RequireRegularFile(const std::filesystem::path& path, const std::string& what = "file");

// RequireRegularFile, and kNotFound, "PATH: WHAT does not exist", when nothing is there.
void RequireExistingFile(const std::filesystem::path& path, const std::string& what);

}  // namespace endorecon
