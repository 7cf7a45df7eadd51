#include "worker/prepare/required_file.h"

#include "common/error.h"

namespace endorecon::prepare {

void RequireRegularFile(const std::filesystem::path& path, const std::string& what) {
  std::error_code error;
  const auto status = std::filesystem::status(path, error);
  if (std::filesystem::is_regular_file(status)) return;
  if (!std::filesystem::exists(status))
    Fail(ErrorCode::kNotFound, path.string() + ": " + what + " does not exist");
  FailInvalid(path.string() + ": " +
              (std::filesystem::is_directory(status) ? "a folder" : "not a regular file") + ", not a " +
              what);
}

}  // namespace endorecon::prepare
