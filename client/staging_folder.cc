#include "client/staging_folder.h"

#include <signal.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <random>

#include "common/error.h"

namespace endorecon::client {
namespace fs = std::filesystem;

namespace {

// endorecon-KIND-PID-N of a process that is gone.
bool LeftByAGoneProcess(const std::string& name, const std::string& prefix) {
  if (name.rfind(prefix, 0) != 0) return false;
  const std::string rest = name.substr(prefix.size());
  const auto dash = rest.find('-');
  if (dash == 0 || dash == std::string::npos) return false;
  char* end = nullptr;
  const long pid = std::strtol(rest.c_str(), &end, 10);
  if (end != rest.c_str() + dash || pid <= 0) return false;
  return ::kill(static_cast<pid_t>(pid), 0) != 0 && errno == ESRCH;
}

}  // namespace

fs::path MakeStagingFolder(const std::string& kind) {
  std::error_code failed;
  const fs::path temp = fs::temp_directory_path(failed);
  const auto refuse = [&](const std::string& why) {
    const char* tmpdir = std::getenv("TMPDIR");
    FailInvalid("cannot make a temporary folder" + (tmpdir && *tmpdir ? " in $TMPDIR " + std::string(tmpdir) : "") +
                " (" + why + "): set TMPDIR to a writable folder");
  };
  if (failed) refuse(failed.message());
  const std::string prefix = "endorecon-" + kind + "-";
  for (fs::directory_iterator it(temp, failed), end; !failed && it != end; it.increment(failed)) {
    std::error_code ignored;
    if (LeftByAGoneProcess(it->path().filename().string(), prefix) && it->is_directory(ignored))
      fs::remove_all(it->path(), ignored);
  }
  const fs::path dir =
      temp / (prefix + std::to_string(::getpid()) + "-" + std::to_string(std::random_device{}()));
  fs::create_directories(dir, failed);
  if (failed) refuse(dir.string() + ": " + failed.message());
  fs::permissions(dir, fs::perms::owner_all, fs::perm_options::replace, failed);
  return dir;
}

}  // namespace endorecon::client
