// What a command says when the system refuses it a local file or folder (std::filesystem's
// exceptions, access(2)): the path, the system's reason, and for a permission the user it runs as.
#pragma once

#include <filesystem>
#include <string>

namespace endorecon {

// "PATH: Permission denied (this command runs as user nobody)": the path(s) the error names and its
// reason. std::filesystem says "filesystem error: status: Permission denied [PATH]".
std::string DescribeFilesystemError(const std::filesystem::filesystem_error& error);

// Whether errno value `error` is a problem of the files the user named (one missing, one this user
// may not use, a read-only disk) rather than of the machine (exit 2 against 1).
bool IsUsersFileProblem(int error);

// " (this command runs as user NAME)" for a refused permission (EACCES, EPERM), else "".
std::string RunsAsNote(int error);

}  // namespace endorecon
