#include "common/json_file.h"

#include <fstream>
#include <iterator>

#include "common/error.h"
#include "common/file_read.h"

namespace endorecon {

nlohmann::json ParseJson(std::string_view text, const std::string& what) {
  const auto depth_check = [&](int depth, nlohmann::json::parse_event_t, nlohmann::json&) {
    if (depth >= kMostJsonDepth)  // depth counts from 0 at the top level
      FailInvalid(what + ": nested deeper than " + std::to_string(kMostJsonDepth) + " levels");
    return true;
  };
  try {
    return nlohmann::json::parse(text.begin(), text.end(), depth_check);
  } catch (const nlohmann::json::exception& e) {
    FailInvalid(what + ": not valid JSON (" + e.what() + ")");
  }
}

nlohmann::json ReadJsonFile(const std::filesystem::path& path) {
  // A pipe would block the read for ever (found 2026-12-05 with a FIFO as transforms.json).
  std::error_code error;
  if (std::filesystem::exists(path, error) && !std::filesystem::is_regular_file(path, error))
    FailInvalid(path.string() + ": not a regular file (a folder, a pipe or a device)");
  std::ifstream in = OpenToRead(path);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  return ParseJson(text, path.string());
}

}  // namespace endorecon
