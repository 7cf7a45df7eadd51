#include "common/json_file.h"

#include <fstream>

#include "common/error.h"

namespace endorecon {

nlohmann::json ReadJsonFile(const std::filesystem::path& path) {
  // A pipe would block the read for ever (found 2026-12-05 with a FIFO as transforms.json).
  std::error_code error;
  if (std::filesystem::exists(path, error) && !std::filesystem::is_regular_file(path, error))
    FailInvalid(path.string() + ": not a regular file (a folder, a pipe or a device)");
  std::ifstream in(path);
  if (!in) FailInvalid(path.string() + ": cannot open the file");
  try {
    return nlohmann::json::parse(in);
  } catch (const nlohmann::json::exception& e) {
    FailInvalid(path.string() + ": not valid JSON (" + e.what() + ")");
  }
}

}  // namespace endorecon
