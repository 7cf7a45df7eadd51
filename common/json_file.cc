#include "common/json_file.h"

#include <fstream>

#include "common/error.h"

namespace endorecon {

nlohmann::json ReadJsonFile(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) FailInvalid(path.string() + ": cannot open the file");
  try {
    return nlohmann::json::parse(in);
  } catch (const nlohmann::json::exception& e) {
    FailInvalid(path.string() + ": not valid JSON (" + e.what() + ")");
  }
}

}  // namespace endorecon
