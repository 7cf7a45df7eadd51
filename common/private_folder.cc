#include "common/private_folder.h"

#include <sys/stat.h>

#include "common/error.h"

namespace endorecon {
namespace fs = std::filesystem;

bool MakePrivateFolder(const fs::path& dir) {
  ::umask(077);
  std::error_code error;
  fs::create_directories(dir, error);
  if (error) FailInvalid("cannot create the folder " + dir.string() + ": " + error.message());
  const auto shared = fs::status(dir, error).permissions() & (fs::perms::group_all | fs::perms::others_all);
  if (error) FailInvalid("cannot read the permissions of " + dir.string() + ": " + error.message());
  return shared != fs::perms::none;
}

}  // namespace endorecon
