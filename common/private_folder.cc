#include "common/private_folder.h"

#include <sys/stat.h>

#include "common/error.h"

namespace endorecon {
namespace fs = std::filesystem;

bool MakePrivateFolder(const fs::path& dir) {
  ::umask(077);
  std::error_code error;
  // The nearest part of `dir` that exists must be a folder: named apart, as "File exists" or "Not a
  // directory" from create_directories left a user to guess which part was meant.
  for (fs::path part = dir; !part.empty(); part = part.parent_path()) {
    const auto kind = fs::status(part, error).type();
    if (kind == fs::file_type::not_found) {
      if (part == part.parent_path()) break;
      continue;
    }
    if (!error && kind != fs::file_type::directory) {
      FailInvalid("cannot use " + dir.string() + " as a folder: " +
                  (part == dir ? std::string("it") : part.string()) + " is a file, not a folder");
    }
    break;
  }
  fs::create_directories(dir, error);
  if (error) FailInvalid("cannot create the folder " + dir.string() + ": " + error.message());
  const auto shared = fs::status(dir, error).permissions() & (fs::perms::group_all | fs::perms::others_all);
  if (error) FailInvalid("cannot read the permissions of " + dir.string() + ": " + error.message());
  return shared != fs::perms::none;
}

}  // namespace endorecon
