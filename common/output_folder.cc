#include "common/output_folder.h"

#include <string>
#include <system_error>

#include "common/error.h"

namespace endorecon {

void CheckOutputFolder(const std::filesystem::path& out, const std::filesystem::path& input, std::string_view what) {
  std::error_code error;
  if (!std::filesystem::is_directory(input, error) || !std::filesystem::exists(out, error)) return;
  if (!std::filesystem::equivalent(out, input, error) || error) return;
  FailInvalid("the output folder " + out.string() + " is " + std::string(what) + " (" + input.string() +
              ") itself: writing there would overwrite its files; choose another output folder");
}

}  // namespace endorecon
